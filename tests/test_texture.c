/* test_texture.c — pbrt-v3's textures (renderer/textures/): Perlin noise (the published
 * permutation, zeros on the lattice, a hand-computed value, agreement with an independent
 * double-precision evaluation of the book's formula, its range), fBm and turbulence
 * against direct sums of octaves, the mappings and the footprint from ray differentials,
 * every procedural texture against values computed by hand at chosen points, the
 * closed-form checkerboard against a brute-force integral of the box-filtered board, the
 * MIP pyramid (exact box averages, the Lanczos resampling against an independent
 * evaluation, odd levels under each wrap mode), bilinear / trilinear / EWA lookups
 * (texel centres, level boundaries, constants, limits), wrap modes, gamma, each image
 * format written here and read back through the texture cache (PNG 8- and 16-bit,
 * palette, grey, interlaced; EXR RGB and Y; PFM colour and grey, both byte orders and a
 * scale; TGA true-colour, grey, colour-mapped, RLE, both orientations), textures made
 * from pbrt-v3 scene text end to end, and the exact sentence of every refusal. Image
 * fixtures are written by the test into a temporary folder; nothing is read from
 * outside it. No statistics: every expectation is exact or has a derived bound. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>

#include <cmocka.h> /* after the three it needs */

#include <math.h>
#include <png.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/arena.h"
#include "core/hash.h"
#include "image/exr.h"
#include "image/image.h"
#include "image/png_encode.h"
#include "pbrt3/pbrt_parser.h"
#include "textures/mipmap.h"
#include "textures/noise.h"
#include "textures/pfm.h"
#include "textures/png_decode.h"
#include "textures/texture.h"
#include "textures/texture_cache.h"
#include "textures/texture_image.h"
#include "textures/texture_mapping.h"
#include "pbrt3/texture_pbrt.h"
#include "textures/tga.h"
#include "tmp_folder.h"

static void write_bytes(const char *rel, const void *data, size_t len)
{
    ts_tmp_write(rel, data, len, NULL, 0);
}

static void assert_close(double a, double b, double tol, const char *what)
{
    if (!(fabs(a - b) <= tol)) fail_msg("%s: %.9g != %.9g (tolerance %g)", what, a, b, tol);
}

static void assert_rgb(ts_rgb v, double r, double g, double b, double tol, const char *what)
{
    char w[160];
    snprintf(w, sizeof w, "%s (r)", what);
    assert_close(v.r, r, tol, w);
    snprintf(w, sizeof w, "%s (g)", what);
    assert_close(v.g, g, tol, w);
    snprintf(w, sizeof w, "%s (b)", what);
    assert_close(v.b, b, tol, w);
}

static void assert_message(const ts_error *err, const char *want)
{
    if (strcmp(err->message, want) != 0) fail_msg("message\n  got:  %s\n  want: %s", err->message, want);
}

static ts_texture_context ctx_uv(float u, float v)
{
    ts_texture_context c = {.uv = {u, v}, .dpdu = {1, 0, 0}, .dpdv = {0, 1, 0}};
    return c;
}

static ts_texture_context ctx_p(float x, float y, float z)
{
    ts_texture_context c = {.p = {x, y, z}, .dpdu = {1, 0, 0}, .dpdv = {0, 1, 0}};
    return c;
}

/* ---------------------------------------------------------------- noise ---- */

/* The book's formula in double, written from its description: the gradient by the low
 * four bits of the hash (u = dx if h < 8 or h ∈ {12, 13}, else dy; v = dy if h < 4 or
 * h ∈ {12, 13}, else dz; signs from bits 0 and 1), a quintic blend. */
static double ref_noise(double x, double y, double z)
{
    const uint8_t *P = ts_noise_permutation();
    double fx = floor(x), fy = floor(y), fz = floor(z);
    int ix = (int)((long long)fx & 255), iy = (int)((long long)fy & 255), iz = (int)((long long)fz & 255);
    double d[3] = {x - fx, y - fy, z - fz};
    double w[2][2][2];
    for (int a = 0; a < 2; a++)
        for (int b = 0; b < 2; b++)
            for (int c = 0; c < 2; c++) {
                int h = P[(P[(P[(ix + a) & 255] + iy + b) & 255] + iz + c) & 255] & 15;
                double dx = d[0] - a, dy = d[1] - b, dz = d[2] - c;
                double u = (h < 8 || h == 12 || h == 13) ? dx : dy;
                double v = (h < 4 || h == 12 || h == 13) ? dy : dz;
                w[a][b][c] = ((h & 1) ? -u : u) + ((h & 2) ? -v : v);
            }
    double q[3];
    for (int k = 0; k < 3; k++)
        q[k] = d[k] * d[k] * d[k] * (d[k] * (d[k] * 6 - 15) + 10);
    double x00 = w[0][0][0] + q[0] * (w[1][0][0] - w[0][0][0]),
           x10 = w[0][1][0] + q[0] * (w[1][1][0] - w[0][1][0]);
    double x01 = w[0][0][1] + q[0] * (w[1][0][1] - w[0][0][1]),
           x11 = w[0][1][1] + q[0] * (w[1][1][1] - w[0][1][1]);
    double y0 = x00 + q[1] * (x10 - x00), y1 = x01 + q[1] * (x11 - x01);
    return y0 + q[2] * (y1 - y0);
}

static void test_noise_permutation(void **state)
{
    (void)state;
    const uint8_t *P = ts_noise_permutation();
    int seen[256] = {0};
    for (int i = 0; i < 256; i++)
        seen[P[i]]++;
    for (int i = 0; i < 256; i++)
        assert_int_equal(seen[i], 1);
    /* Perlin's published table opens 151, 160, 137, 91, 90, 15 and closes 156, 180. */
    assert_int_equal(P[0], 151), assert_int_equal(P[1], 160), assert_int_equal(P[2], 137);
    assert_int_equal(P[3], 91), assert_int_equal(P[4], 90), assert_int_equal(P[5], 15);
    assert_int_equal(P[254], 156), assert_int_equal(P[255], 180);
}

static void test_noise_values(void **state)
{
    (void)state;
    /* 0 at every lattice point, negative and far ones included. */
    const float lattice[][3] = {{0, 0, 0},       {1, 2, 3},           {-1, -7, 12},
                                {255, 256, 257}, {-1000, 4096, 1e6f}, {3e9f, -2e10f, 7}};
    for (size_t i = 0; i < sizeof lattice / sizeof lattice[0]; i++)
        assert_true(ts_noise(lattice[i][0], lattice[i][1], lattice[i][2]) == 0);
    /* By hand: at (0.25, 0, 0) only the corners (0,0,0) and (1,0,0) count (the blend
     * weights in y and z are 0). Their hashes: P[P[P[0]]] = P[P[151]] = P[17] = 36 →
     * h = 4, gradient (1, 0, 1); P[P[P[1]]] = P[P[160]] = P[119] → h = 6, (1, 0, −1). So
     * the weights are 1·0.25 and 1·(−0.75), blended by w = 6t⁵ − 15t⁴ + 10t³ at t = ¼,
     * 0.103515625: 0.75·0.25 − … = 0.25 − w = 0.146484375 (all dyadic: exact in float). */
    const uint8_t *P = ts_noise_permutation();
    assert_int_equal(P[151], 17), assert_int_equal(P[17], 36), assert_int_equal(P[160], 119);
    assert_int_equal(P[119] & 15, 6);
    assert_true(ts_noise(0.25f, 0, 0) == 0.146484375f);
    /* Non-finite input gives 0. */
    assert_true(ts_noise(NAN, 0, 0) == 0 && ts_noise(0, INFINITY, 0) == 0);

    /* Against the double-precision formula at 100000 points (fixed seed): the float
     * evaluation is about 40 roundings, each at most half an ulp of a value ≤ 2
     * (1.2e-7), so it is within 5e-6 of the exact value. */
    ts_pcg32 rng;
    ts_pcg32_seed(&rng, 7, 0);
    double worst = 0, max_abs = 0;
    for (int i = 0; i < 100000; i++) {
        float x = (ts_pcg32_float(&rng) - 0.5f) * 600, y = (ts_pcg32_float(&rng) - 0.5f) * 600,
              z = (ts_pcg32_float(&rng) - 0.5f) * 600;
        double got = ts_noise(x, y, z), want = ref_noise(x, y, z);
        if (fabs(got - want) > worst) worst = fabs(got - want);
        if (fabs(got) > max_abs) max_abs = fabs(got);
        /* The provable bound: a convex blend of corner weights |g·d| ≤ |d_i| + |d_j| ≤ 2. */
        assert_true(fabs(got) <= 2);
    }
    print_message("noise vs double formula: max |diff| %.3g; max |noise| over the sample %.6f\n", worst,
                  max_abs);
    assert_true(worst < 5e-6);
    /* pbrt-v3's noise is not bounded by 1: a local search found 1.01647 here (pinned as
     * a regression; the sample above stays below it). */
    assert_close(fabs(ts_noise(41.4827f, 230.417f, 129.509f)), 1.01647, 1e-4,
                 "noise maximum found by search");
}

static void test_fbm_turbulence(void **state)
{
    (void)state;
    ts_vec3 p = {1.37f, -2.71f, 0.577f}, zero = {0, 0, 0};
    const float omega = 0.6f;
    /* No footprint: all 8 octaves. The fractional octave has weight smoothstep(0) = 0 in
     * fBm; in turbulence it is lerp(0, 0.2, |noise|) = 0.2 at weight ω^8 (pbrt-v3 adds it
     * even when no octave was clamped). */
    double fbm = 0, turb = 0, o = 1, lambda = 1;
    for (int i = 0; i < 8; i++) {
        float l = (float)lambda;
        double n = ts_noise(l * p.x, l * p.y, l * p.z);
        fbm += o * n, turb += o * fabs(n);
        o *= omega, lambda = (float)(lambda * 1.99f);
    }
    assert_close(ts_noise_fbm(p, zero, zero, omega, 8), fbm, 1e-6, "fbm, 8 octaves");
    assert_close(ts_noise_turbulence(p, zero, zero, omega, 8), turb + o * 0.2, 1e-6, "turbulence, 8 octaves");

    /* |∂p/∂x|² = 2^-9: n = −1 − ½·log₂ 2^-9 = 3.5, so 3 octaves and half of the 4th faded
     * by smoothstep(0.3, 0.7, 0.5) = 0.5; turbulence adds 0.2·ω^i for i = 3 … 7 (pbrt-v3
     * keeps the 4th octave's weight for the first of them). */
    ts_vec3 dx = {sqrtf(0x1p-9f), 0, 0}, dy = {0, 0.01f, 0};
    assert_close(ts_noise_octaves(dx, dy, 8), 3.5, 1e-5, "octaves");
    fbm = turb = 0, o = 1, lambda = 1;
    for (int i = 0; i < 3; i++) {
        float l = (float)lambda;
        double n = ts_noise(l * p.x, l * p.y, l * p.z);
        fbm += o * n, turb += o * fabs(n);
        o *= omega, lambda = (float)(lambda * 1.99f);
    }
    float l = (float)lambda;
    double n3 = ts_noise(l * p.x, l * p.y, l * p.z);
    fbm += o * 0.5 * n3;
    turb += o * (0.5 * 0.2 + 0.5 * fabs(n3));
    for (int i = 3; i < 8; i++)
        turb += o * 0.2, o *= omega;
    /* smoothstep's slope at 0.5 is 1.5: the 1e-5 tolerance of n covers float log2. */
    assert_close(ts_noise_fbm(p, dx, dy, omega, 8), fbm, 2e-5, "fbm, 3.5 octaves");
    assert_close(ts_noise_turbulence(p, dx, dy, omega, 8), turb, 2e-5, "turbulence, 3.5 octaves");

    /* A footprint wider than the noise: no octave; turbulence is all averages. */
    ts_vec3 big = {10, 0, 0};
    assert_true(ts_noise_fbm(p, big, zero, omega, 8) == 0);
    double avg = 0.2, w = 1;
    for (int i = 0; i < 8; i++)
        avg += 0.2 * w, w *= omega;
    assert_close(ts_noise_turbulence(p, big, zero, omega, 8), avg, 1e-6, "turbulence, 0 octaves");
    /* A NaN footprint counts as none. */
    ts_vec3 nan3 = {NAN, 0, 0};
    assert_true(ts_noise_fbm(p, nan3, zero, omega, 8) == ts_noise_fbm(p, zero, zero, omega, 8));
}

/* ------------------------------------------------------------- mappings ---- */

static void test_mappings(void **state)
{
    (void)state;
    ts_texture_context c = ctx_uv(0.25f, 0.5f);
    c.dudx = 0.01f, c.dvdx = 0.02f, c.dudy = -0.03f, c.dvdy = 0.04f;
    ts_vec2 dx, dy;
    ts_texture_mapping2d uv = ts_texture_mapping2d_uv(2, 3, 0.5f, -1);
    ts_vec2 st = ts_texture_mapping2d_map(&uv, &c, &dx, &dy);
    assert_true(st.x == 1.0f && st.y == 0.5f);
    assert_true(dx.x == 0.02f && dx.y == 0.06f && dy.x == -0.06f && dy.y == 0.12f);

    /* Spherical: θ/π from +z, φ/2π from +x towards +y, about texture space's origin
     * (here world shifted by (0, 0, −1): world→texture translates by +1 in z... the
     * matrix below maps world p to p − (0, 0, 1)). */
    ts_mat4 w2t = ts_mat4_identity();
    w2t.m[2][3] = -1;
    ts_texture_mapping2d sph = ts_texture_mapping2d_spherical(&w2t);
    c = ctx_p(0, 0, 3); /* straight up from (0, 0, 1) */
    st = ts_texture_mapping2d_map(&sph, &c, &dx, &dy);
    assert_close(st.x, 0, 1e-7, "sphere θ at the pole");
    c = ctx_p(0, 2, 1); /* along +y: θ = π/2, φ = π/2 */
    st = ts_texture_mapping2d_map(&sph, &c, &dx, &dy);
    assert_close(st.x, 0.5, 1e-6, "sphere θ"), assert_close(st.y, 0.25, 1e-6, "sphere φ");
    /* Derivative by pbrt-v3's forward difference of 0.1·∂p/∂x: from (1, 0) to
     * (1, 0.01): Δφ = atan(0.01). */
    c = ctx_p(1, 0, 1);
    c.dpdx = (ts_vec3){0, 0.1f, 0};
    st = ts_texture_mapping2d_map(&sph, &c, &dx, &dy);
    assert_close(dx.y, atan(0.01) / (2 * M_PI) / 0.1, 1e-5, "sphere ∂t/∂x");
    assert_close(dx.x, 0, 1e-6, "sphere ∂s/∂x"), assert_true(dy.x == 0 && dy.y == 0);
    /* Across φ = 2π the difference quotient is corrected as pbrt-v3 does it: −(d + 1). */
    c = ctx_p(1, -0.001f, 1);
    c.dpdx = (ts_vec3){0, 0.1f, 0};
    st = ts_texture_mapping2d_map(&sph, &c, &dx, &dy);
    double t0 = (2 * M_PI - atan(0.001)) / (2 * M_PI), t1 = atan(0.009) / (2 * M_PI);
    assert_close(st.y, t0, 1e-6, "sphere φ near 2π");
    assert_close(dx.y, -((t1 - t0) / 0.1 + 1), 1e-4, "sphere wrap correction");

    /* Cylindrical: ((π + atan2(y, x))/2π, z) of the normalised point. */
    ts_mat4 id = ts_mat4_identity();
    ts_texture_mapping2d cyl = ts_texture_mapping2d_cylindrical(&id);
    c = ctx_p(1, 0, 0.5f);
    st = ts_texture_mapping2d_map(&cyl, &c, &dx, &dy);
    assert_close(st.x, 0.5, 1e-6, "cylinder s"), assert_close(st.y, 0.5 / sqrt(1.25), 1e-6, "cylinder t");
    c = ctx_p(0, -1, 0);
    st = ts_texture_mapping2d_map(&cyl, &c, &dx, &dy);
    assert_close(st.x, 0.25, 1e-6, "cylinder s at −y");

    /* Planar: world p on the two axes, plus the offsets; derivatives the axes · ∂p. */
    ts_texture_mapping2d pl =
        ts_texture_mapping2d_planar((ts_vec3){1, 0, 0}, (ts_vec3){0, 0, 2}, 0.5f, 0.25f);
    c = ctx_p(3, 7, 1);
    c.dpdx = (ts_vec3){0.1f, 5, 0.2f}, c.dpdy = (ts_vec3){0, 0, -1};
    st = ts_texture_mapping2d_map(&pl, &c, &dx, &dy);
    assert_true(st.x == 3.5f && st.y == 2.25f);
    assert_true(dx.x == 0.1f && dx.y == 0.4f && dy.x == 0 && dy.y == -2);

    /* 3D: the transform of p and of the footprint's vectors. */
    ts_texture_mapping3d m3 = {ts_mat4_identity()};
    m3.world_to_texture.m[0][0] = 2, m3.world_to_texture.m[1][3] = 5;
    c = ctx_p(1, 2, 3);
    c.dpdx = (ts_vec3){1, 1, 1};
    ts_vec3 d3x, d3y, p3 = ts_texture_mapping3d_map(&m3, &c, &d3x, &d3y);
    assert_true(p3.x == 2 && p3.y == 7 && p3.z == 3);
    assert_true(d3x.x == 2 && d3x.y == 1 && d3x.z == 1 && d3y.x == 0);
}

static void test_differentials(void **state)
{
    (void)state;
    /* The plane z = 0 with u = x, v = y; offset rays from above. */
    ts_texture_context c = ctx_p(0, 0, 0);
    ts_vec3 n = {0, 0, 1};
    ts_texture_context_set_differentials(&c, n, (ts_vec3){0.1f, 0, 1}, (ts_vec3){0, 0, -1},
                                         (ts_vec3){0, 0.2f, 1}, (ts_vec3){0, 0.1f, -1});
    assert_close(c.dpdx.x, 0.1, 1e-7, "dpdx"), assert_close(c.dpdy.y, 0.3, 1e-6, "dpdy");
    assert_close(c.dudx, 0.1, 1e-7, "dudx"), assert_close(c.dvdx, 0, 1e-7, "dvdx");
    assert_close(c.dudy, 0, 1e-7, "dudy"), assert_close(c.dvdy, 0.3, 1e-6, "dvdy");
    /* A stretched parameterisation (u = x/2): du doubles. */
    c.dpdu = (ts_vec3){2, 0, 0};
    ts_texture_context_set_differentials(&c, n, (ts_vec3){0.1f, 0, 1}, (ts_vec3){0, 0, -1},
                                         (ts_vec3){0, 0.2f, 1}, (ts_vec3){0, 0, -1});
    assert_close(c.dudx, 0.05, 1e-7, "dudx stretched");
    /* An offset ray parallel to the plane: no footprint at all. */
    ts_texture_context_set_differentials(&c, n, (ts_vec3){0, 0, 1}, (ts_vec3){1, 0, 0}, (ts_vec3){0, 0, 1},
                                         (ts_vec3){0, 0, -1});
    assert_true(c.dpdx.x == 0 && c.dpdy.y == 0 && c.dudx == 0 && c.dvdy == 0);
    /* Degenerate (u, v): the plane is hit but du, dv are 0. */
    c.dpdu = (ts_vec3){0, 0, 0};
    ts_texture_context_set_differentials(&c, n, (ts_vec3){0.1f, 0, 1}, (ts_vec3){0, 0, -1},
                                         (ts_vec3){0, 0.2f, 1}, (ts_vec3){0, 0, -1});
    assert_close(c.dpdx.x, 0.1, 1e-7, "dpdx kept");
    assert_true(c.dudx == 0 && c.dvdx == 0);
}

/* ------------------------------------------------------ procedural textures ---- */

static ts_arena arena;

static const ts_texture *mk(const ts_texture *proto)
{
    const ts_texture *t = NULL;
    ts_error err = {0};
    if (ts_texture_make(&arena, proto, &t, &err)) fail_msg("ts_texture_make: %s", err.message);
    return t;
}

static const ts_texture *cf(float v)
{
    ts_texture p = ts_texture_constant_float(v);
    return mk(&p);
}

static const ts_texture *crgb(float r, float g, float b)
{
    ts_texture p = ts_texture_constant_rgb((ts_rgb){r, g, b});
    return mk(&p);
}

static int setup_arena(void **state)
{
    (void)state;
    ts_arena_init(&arena, 0);
    return 0;
}

static int teardown_arena(void **state)
{
    (void)state;
    ts_arena_fini(&arena);
    return 0;
}

static void test_basic_textures(void **state)
{
    (void)state;
    ts_texture_context c = ctx_uv(0.25f, 0.75f);
    assert_true(ts_texture_eval_float(cf(0.5f), &c) == 0.5f);
    assert_rgb(ts_texture_eval_rgb(crgb(1, 2, 3), &c), 1, 2, 3, 0, "constant rgb");
    ts_texture s = {.type = TS_TEXTURE_SCALE, .scale = {cf(0.5f), cf(3)}};
    assert_true(ts_texture_eval_float(mk(&s), &c) == 1.5f);
    ts_texture sr = {
        .type = TS_TEXTURE_SCALE, .is_rgb = true, .scale = {crgb(1, 2, 3), crgb(0.5f, 0.25f, 2)}};
    assert_rgb(ts_texture_eval_rgb(mk(&sr), &c), 0.5, 0.5, 6, 0, "scale rgb");
    ts_texture mx = {
        .type = TS_TEXTURE_MIX, .is_rgb = true, .mix = {crgb(1, 0, 0), crgb(0, 0, 4), cf(0.25f)}};
    assert_rgb(ts_texture_eval_rgb(mk(&mx), &c), 0.75, 0, 1, 0, "mix");
    /* (1−s)(1−t)·1 + (1−s)t·2 + s(1−t)·3 + st·4 at (¼, ¾) = 0.1875 + 1.125 + 0.1875 + 0.75. */
    ts_texture bl = {.type = TS_TEXTURE_BILERP,
                     .bilerp = {ts_texture_mapping2d_uv(1, 1, 0, 0), ts_rgb_gray(1), ts_rgb_gray(2),
                                ts_rgb_gray(3), ts_rgb_gray(4)}};
    assert_true(ts_texture_eval_float(mk(&bl), &c) == 2.25f);
    ts_texture uvt = {.type = TS_TEXTURE_UV, .is_rgb = true, .uv = {ts_texture_mapping2d_uv(1, 1, 1, -1)}};
    assert_rgb(ts_texture_eval_rgb(mk(&uvt), &c), 0.25, 0.75, 0, 0, "uv (wrapped)");
}

static void test_checkerboard_point(void **state)
{
    (void)state;
    const ts_texture *one = cf(1), *two = cf(2);
    ts_texture cb = {.type = TS_TEXTURE_CHECKERBOARD2D,
                     .checkerboard2d = {ts_texture_mapping2d_uv(1, 1, 0, 0), one, two, false}};
    const ts_texture *t = mk(&cb);
    const float pts[][3] = {{0.5f, 0.5f, 1},   {1.5f, 0.5f, 2},  {-0.5f, 0.5f, 2},
                            {-0.5f, -0.5f, 1}, {7.2f, -3.9f, 2}, {1e9f, 0.5f, 1}};
    for (size_t i = 0; i < sizeof pts / sizeof pts[0]; i++) {
        ts_texture_context c = ctx_uv(pts[i][0], pts[i][1]);
        c.dudx = 0.3f; /* ignored without the closed form */
        assert_true(ts_texture_eval_float(t, &c) == pts[i][2]);
    }
    ts_mat4 m = ts_mat4_identity();
    ts_texture cb3 = {.type = TS_TEXTURE_CHECKERBOARD3D, .checkerboard3d = {{m}, one, two}};
    t = mk(&cb3);
    const float p3[][4] = {{0.5f, 0.5f, 0.5f, 1},  {1.5f, 0.5f, 0.5f, 2},    {1.5f, 1.5f, 0.5f, 1},
                           {-0.5f, 0.5f, 0.5f, 2}, {-0.5f, -0.5f, -0.5f, 2}, {2.5f, -1.5f, 3.5f, 2},
                           {2.5f, -0.5f, 3.5f, 1}};
    for (size_t i = 0; i < sizeof p3 / sizeof p3[0]; i++) {
        ts_texture_context c = ctx_p(p3[i][0], p3[i][1], p3[i][2]);
        assert_true(ts_texture_eval_float(t, &c) == p3[i][3]);
    }
}

/* The box-filtered checkerboard by brute force: the fraction of an N × N midpoint grid
 * over the box that falls on odd checks. Each check edge crossing the box misassigns at
 * most one grid column or row of area 1/N of the box: with ds, dt ≤ 1 at most 3 edges
 * cross each axis, so the error is ≤ 6/N. */
static double brute_odd_fraction(double s, double t, double ds, double dt, int n)
{
    long odd = 0;
    for (int j = 0; j < n; j++) {
        double y = t - dt + (2 * dt) * (j + 0.5) / n;
        long py = (long)floor(y) & 1;
        for (int i = 0; i < n; i++) {
            double x = s - ds + (2 * ds) * (i + 0.5) / n;
            odd += ((long)floor(x) & 1) ^ py;
        }
    }
    return (double)odd / ((double)n * n);
}

static void test_checkerboard_closed_form(void **state)
{
    (void)state;
    const int n = 3000;
    const double tol = 6.0 / n + 1e-5; /* + float rounding of the closed form */
    const float cases[][4] = {
        {0.5f, 0.5f, 0.7f, 0.2f},  {0.1f, 0.9f, 0.3f, 0.3f},     {1.02f, -0.4f, 0.05f, 0.9f},
        {-2.3f, 5.6f, 1.0f, 0.4f}, {3.99f, 3.99f, 0.02f, 0.02f}, {10.5f, -7.25f, 0.9f, 0.95f},
        {0.0f, 0.0f, 0.5f, 0.5f},  {-0.75f, 2.2f, 0.6f, 1.0f},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        ts_vec2 st = {cases[i][0], cases[i][1]};
        float ds = cases[i][2], dt = cases[i][3];
        double got = ts_texture_checkerboard_odd_fraction(st, ds, dt);
        double want = brute_odd_fraction(st.x, st.y, ds, dt, n);
        char what[96];
        snprintf(what, sizeof what, "box at (%g, %g) ± (%g, %g)", (double)st.x, (double)st.y, (double)ds,
                 (double)dt);
        assert_close(got, want, tol, what);
    }
    /* A box inside one check: that check's texture exactly. */
    assert_true(ts_texture_checkerboard_odd_fraction((ts_vec2){0.5f, 0.5f}, 0.1f, 0.1f) == 0);
    assert_true(ts_texture_checkerboard_odd_fraction((ts_vec2){1.5f, 0.5f}, 0.1f, 0.1f) == 1);
    /* Wider than a check (half-width > 1): pbrt-v3's 0.5. */
    assert_true(ts_texture_checkerboard_odd_fraction((ts_vec2){0.3f, 0.2f}, 1.5f, 0.1f) == 0.5f);
    /* A zero half-width on one axis while the other crosses an edge: the limit, never
     * pbrt-v3's 0/0. At s = 0.5 (even column) the fraction is the t-average. */
    double lim = ts_texture_checkerboard_odd_fraction((ts_vec2){0.5f, 0.9f}, 0, 0.2f);
    assert_close(lim, brute_odd_fraction(0.5, 0.9, 1e-9, 0.2, n), tol, "zero half-width");

    /* Through the texture: the blend of tex1 and tex2 by that fraction, from the uv
     * footprint (ds = max |∂s/∂x|, |∂s/∂y|). */
    ts_texture cb = {
        .type = TS_TEXTURE_CHECKERBOARD2D,
        .is_rgb = true,
        .checkerboard2d = {ts_texture_mapping2d_uv(2, 2, 0, 0), crgb(1, 1, 1), crgb(0, 0, 0), true}};
    const ts_texture *t = mk(&cb);
    ts_texture_context c = ctx_uv(0.25f, 0.3f);     /* st (0.5, 0.6) */
    c.dudx = 0.1f, c.dvdy = -0.35f, c.dudy = 0.05f; /* ds = 0.2, dt = 0.7 */
    double a = ts_texture_checkerboard_odd_fraction((ts_vec2){0.5f, 0.6f}, 0.2f, 0.7f);
    assert_true(a > 0 && a < 1);
    assert_rgb(ts_texture_eval_rgb(t, &c), 1 - a, 1 - a, 1 - a, 1e-6, "filtered checkerboard");
}

static void test_noise_textures(void **state)
{
    (void)state;
    ts_mat4 scale2 = ts_mat4_identity();
    scale2.m[0][0] = scale2.m[1][1] = scale2.m[2][2] = 2;
    ts_texture_context c = ctx_p(0.3f, -1.7f, 2.2f);
    c.dpdx = (ts_vec3){0.01f, 0, 0}, c.dpdy = (ts_vec3){0, 0.02f, 0};
    ts_vec3 p2 = {0.6f, -3.4f, 4.4f}, dx2 = {0.02f, 0, 0}, dy2 = {0, 0.04f, 0};

    ts_texture f = {.type = TS_TEXTURE_FBM, .fbm = {{scale2}, 6, 0.4f}};
    assert_true(ts_texture_eval_float(mk(&f), &c) == ts_noise_fbm(p2, dx2, dy2, 0.4f, 6));
    ts_texture w = {.type = TS_TEXTURE_WRINKLED, .fbm = {{scale2}, 6, 0.4f}};
    assert_true(ts_texture_eval_float(mk(&w), &c) == ts_noise_turbulence(p2, dx2, dy2, 0.4f, 6));
    ts_texture wy = {.type = TS_TEXTURE_WINDY, .windy = {{scale2}}};
    float wind =
        ts_noise_fbm(ts_vec3_scale(p2, .1f), ts_vec3_scale(dx2, .1f), ts_vec3_scale(dy2, .1f), .5f, 3);
    float wave = ts_noise_fbm(p2, dx2, dy2, .5f, 6);
    assert_true(ts_texture_eval_float(mk(&wy), &c) == fabsf(wind) * wave);
    /* At the origin every octave is 0. */
    ts_texture_context c0 = ctx_p(0, 0, 0);
    assert_true(ts_texture_eval_float(mk(&wy), &c0) == 0);

    /* Marble with variation 0: t = ½ + ½ sin(scale·p_y), then the spline by hand:
     * t = ½ → 6t = 3: segment 3 at 0, the colour c3 = (.5, .5, .5), × 1.5;
     * t = 1 → segment 5 (not 6) at 1: c8 = (.58, .58, .6) × 1.5;
     * t = ¼ → 6t = 1.5: segment 1 at ½: (c1 + 3c2 + 3c3 + c4)/8 × 1.5 with c1 = c2 =
     *   (.58, .58, .6), c3 = (.5, .5, .5), c4 = (.6, .59, .58). */
    ts_mat4 id = ts_mat4_identity();
    ts_texture mb = {.type = TS_TEXTURE_MARBLE, .is_rgb = true, .marble = {{id}, 8, 0.5f, 2, 0}};
    const ts_texture *m = mk(&mb);
    c = ctx_p(5, 0, -3);
    assert_rgb(ts_texture_eval_rgb(m, &c), 0.75, 0.75, 0.75, 1e-6, "marble t = 1/2");
    c = ctx_p(0, (float)(M_PI / 4), 0); /* scale 2: sin(π/2) = 1 */
    assert_rgb(ts_texture_eval_rgb(m, &c), 0.87, 0.87, 0.9, 1e-5, "marble t = 1");
    c = ctx_p(0, (float)(-M_PI / 12), 0); /* sin(−π/6) = −½ */
    assert_rgb(ts_texture_eval_rgb(m, &c), 1.5 * (0.58 + 3 * 0.58 + 3 * 0.5 + 0.6) / 8,
               1.5 * (0.58 + 3 * 0.58 + 3 * 0.5 + 0.59) / 8, 1.5 * (0.6 + 3 * 0.6 + 3 * 0.5 + 0.58) / 8, 1e-5,
               "marble t = 1/4");
    /* Over many points its colours stay within the spline's hull, [0.3, 0.9]. */
    ts_texture mb2 = {.type = TS_TEXTURE_MARBLE, .is_rgb = true, .marble = {{id}, 8, 0.5f, 1, 5}};
    m = mk(&mb2);
    ts_pcg32 rng;
    ts_pcg32_seed(&rng, 3, 0);
    for (int i = 0; i < 20000; i++) {
        c = ctx_p(ts_pcg32_float(&rng) * 20, ts_pcg32_float(&rng) * 20, ts_pcg32_float(&rng) * 20);
        ts_rgb v = ts_texture_eval_rgb(m, &c);
        assert_true(v.r >= 0.3f - 1e-6f && v.r <= 0.9f + 1e-6f && v.b >= 0.3f - 1e-6f && v.b <= 0.9f + 1e-6f);
    }
}

static void test_dots(void **state)
{
    (void)state;
    ts_texture d = {.type = TS_TEXTURE_DOTS, .dots = {ts_texture_mapping2d_uv(1, 1, 0, 0), cf(1), cf(0)}};
    const ts_texture *t = mk(&d);
    /* The rule by hand at a grid of points: cell ⌊s + ½⌋, a dot there when
     * Noise(cell + ½, ½) > 0, centred at cell + 0.15·(Noise(s+1.5, t+2.8), Noise(s+4.5,
     * t+9.8)), radius 0.35. */
    int inside = 0, outside = 0;
    for (int j = 0; j < 40; j++)
        for (int i = 0; i < 40; i++) {
            float s = -5 + i * 0.27f, u = -3 + j * 0.31f;
            float sc = floorf(s + .5f), tc = floorf(u + .5f);
            float want = 0;
            if (ts_noise(sc + .5f, tc + .5f, .5f) > 0) {
                float cs = sc + 0.15f * ts_noise(sc + 1.5f, tc + 2.8f, .5f);
                float ct = tc + 0.15f * ts_noise(sc + 4.5f, tc + 9.8f, .5f);
                if ((s - cs) * (s - cs) + (u - ct) * (u - ct) < 0.35f * 0.35f) want = 1;
            }
            ts_texture_context c = ctx_uv(s, u);
            assert_true(ts_texture_eval_float(t, &c) == want);
            want ? inside++ : outside++;
        }
    print_message("dots: %d inside, %d outside of 1600 points\n", inside, outside);
    assert_true(inside > 100 && outside > 100); /* the grid sees both */
}

/* ------------------------------------------------------------- MIP maps ---- */

static ts_mipmap *mkmap(const float *tx, int w, int h, int nc, ts_texture_wrap wrap)
{
    ts_mipmap *m = NULL;
    ts_error err = {0};
    if (ts_mipmap_create(tx, w, h, nc, wrap, 0, &m, &err)) fail_msg("ts_mipmap_create: %s", err.message);
    return m;
}

static void test_mipmap_pyramid(void **state)
{
    (void)state;
    /* 4 × 4 RGB with values on a 1/8 grid: the 2 × 2 box averages are exact in float. */
    float tx[4 * 4 * 3];
    for (int t = 0; t < 4; t++)
        for (int s = 0; s < 4; s++)
            for (int k = 0; k < 3; k++)
                tx[(t * 4 + s) * 3 + k] = (float)((s * 5 + t * 3 + k * 7) % 16) / 8;
    ts_mipmap *m = mkmap(tx, 4, 4, 3, TS_TEXTURE_WRAP_REPEAT);
    assert_int_equal(m->n_levels, 3);
    assert_int_equal(m->levels[1].width, 2), assert_int_equal(m->levels[2].width, 1);
    assert_int_equal(m->bytes, (16 + 4 + 1) * 3 * sizeof(float));
    double mean[3] = {0, 0, 0};
    for (int t = 0; t < 2; t++)
        for (int s = 0; s < 2; s++) {
            ts_rgb v = ts_mipmap_texel(m, 1, s, t);
            float want[3] = {0, 0, 0};
            for (int k = 0; k < 3; k++) {
                for (int dt = 0; dt < 2; dt++)
                    for (int ds = 0; ds < 2; ds++)
                        want[k] += tx[((2 * t + dt) * 4 + 2 * s + ds) * 3 + k];
                want[k] /= 4;
                mean[k] += want[k] / 4;
            }
            assert_true(v.r == want[0] && v.g == want[1] && v.b == want[2]);
        }
    ts_rgb top = ts_mipmap_texel(m, 2, 0, 0);
    assert_true(top.r == (float)mean[0] && top.g == (float)mean[1] && top.b == (float)mean[2]);
    /* Level 0 is the image itself; the repeat wrap at every level. */
    assert_true(ts_mipmap_texel(m, 0, 1, 2).g == tx[(2 * 4 + 1) * 3 + 1]);
    assert_true(ts_mipmap_texel(m, 0, -3, 6).r == tx[(2 * 4 + 1) * 3]);
    assert_true(ts_mipmap_texel(m, 1, 3, -1).b == ts_mipmap_texel(m, 1, 1, 1).b);
    ts_mipmap_destroy(m);

    /* A 4 × 1 image: level 1 (2 × 1) pairs each texel row with the row the wrap mode
     * gives for t = 1: itself (repeat, clamp) or black (pbrt-v3 does the same). */
    float row[4] = {1, 3, 5, 7};
    const ts_texture_wrap wraps[3] = {TS_TEXTURE_WRAP_REPEAT, TS_TEXTURE_WRAP_CLAMP, TS_TEXTURE_WRAP_BLACK};
    for (int i = 0; i < 3; i++) {
        m = mkmap(row, 4, 1, 1, wraps[i]);
        assert_int_equal(m->n_levels, 3);
        float f = wraps[i] == TS_TEXTURE_WRAP_BLACK ? 0.5f : 1.0f;
        assert_true(ts_mipmap_texel(m, 1, 0, 0).r == 2 * f && ts_mipmap_texel(m, 1, 1, 0).r == 6 * f);
        assert_true(ts_mipmap_texel(m, 2, 0, 0).r == 4 * f * f);
        ts_mipmap_destroy(m);
    }
}

/* pbrt-v3's resampling weights, in double, from the book's description: new texel i of
 * n has centre (i + ½)·old/new; four taps starting at ⌊centre − 2 + ½⌋ at positions
 * tap + ½, weighted by the Lanczos window sinc(2x)·sinc(x) of (pos − centre)/2, and
 * normalised. */
static void ref_weights(int old_res, int new_res, int i, int *first, double w[4])
{
    double center = (i + 0.5) * old_res / new_res;
    *first = (int)floor(center - 2 + 0.5);
    double sum = 0;
    for (int j = 0; j < 4; j++) {
        double x = fabs((*first + j + 0.5 - center) / 2);
        double v = x < 1e-5 ? 1 : x > 1 ? 0 : sin(2 * M_PI * x) / (2 * M_PI * x) * sin(M_PI * x) / (M_PI * x);
        w[j] = v, sum += v;
    }
    for (int j = 0; j < 4; j++)
        w[j] /= sum;
}

/* Tap i of n under a wrap mode (repeat, clamp, black: -1 outside). */
static int ref_tap(int i, int n, ts_texture_wrap wrap)
{
    if (wrap == TS_TEXTURE_WRAP_REPEAT) return ((i % n) + n) % n;
    if (wrap == TS_TEXTURE_WRAP_CLAMP) return i < 0 ? 0 : i >= n ? n - 1 : i;
    return i >= 0 && i < n ? i : -1;
}

static void test_mipmap_resample(void **state)
{
    (void)state;
    /* 3 × 5 grey image under each wrap mode: level 0 becomes 4 × 8, the s pass then the
     * t pass, clamped at 0 — against the weights evaluated in double. Float weights and
     * sums of 4 + 4 terms of magnitude ≤ 1.5 are within 2e-6. */
    float tx[15];
    for (int i = 0; i < 15; i++)
        tx[i] = (float)((i * 7) % 11) / 10;
    for (int wi = 0; wi < 3; wi++) {
        ts_texture_wrap wrap = (ts_texture_wrap)wi;
        ts_mipmap *m = mkmap(tx, 3, 5, 1, wrap);
        assert_int_equal(m->levels[0].width, 4), assert_int_equal(m->levels[0].height, 8);
        assert_int_equal(m->n_levels, 4);
        assert_int_equal(m->source_width, 3), assert_int_equal(m->source_height, 5);
        double spass[5][4];
        for (int t = 0; t < 5; t++)
            for (int s = 0; s < 4; s++) {
                int first;
                double w[4];
                ref_weights(3, 4, s, &first, w);
                spass[t][s] = 0;
                for (int j = 0; j < 4; j++) {
                    int k = ref_tap(first + j, 3, wrap);
                    if (k >= 0) spass[t][s] += w[j] * tx[t * 3 + k];
                }
            }
        for (int t = 0; t < 8; t++)
            for (int s = 0; s < 4; s++) {
                int first;
                double w[4], v = 0;
                ref_weights(5, 8, t, &first, w);
                for (int j = 0; j < 4; j++) {
                    int k = ref_tap(first + j, 5, wrap);
                    if (k >= 0) v += w[j] * spass[k][s];
                }
                if (v < 0) v = 0;
                char what[64];
                snprintf(what, sizeof what, "wrap %d: resampled texel (%d, %d)", wi, s, t);
                assert_close(ts_mipmap_texel(m, 0, s, t).r, v, 2e-6, what);
            }
        ts_mipmap_destroy(m);
    }

    /* A constant image stays constant under repeat and clamp (the weights sum to 1);
     * under black its border darkens. */
    float k[6 * 3];
    for (int i = 0; i < 18; i++)
        k[i] = 0.7f;
    for (int wi = 0; wi < 3; wi++) {
        ts_texture_wrap wrap = (ts_texture_wrap)wi;
        ts_mipmap *m = mkmap(k, 6, 3, 1, wrap);
        if (wrap == TS_TEXTURE_WRAP_BLACK) {
            assert_true(ts_mipmap_texel(m, 0, 0, 0).r < 0.69f);
        } else {
            for (int t = 0; t < 4; t++)
                for (int s = 0; s < 8; s++)
                    assert_close(ts_mipmap_texel(m, 0, s, t).r, 0.7, 1e-6, "constant");
        }
        ts_mipmap_destroy(m);
    }
}

static void test_mipmap_lookups(void **state)
{
    (void)state;
    /* 8 × 8 grey ramp-and-checks, repeat. */
    float tx[64];
    for (int t = 0; t < 8; t++)
        for (int s = 0; s < 8; s++)
            tx[t * 8 + s] = (float)s / 8 + ((s + t) % 2) * 0.25f;
    ts_mipmap *m = mkmap(tx, 8, 8, 1, TS_TEXTURE_WRAP_REPEAT);
    /* Bilinear at texel centres is the texel; halfway it is the mean of the two. */
    assert_true(ts_mipmap_bilinear(m, 0, (ts_vec2){2.5f / 8, 5.5f / 8}).r == tx[5 * 8 + 2]);
    assert_close(ts_mipmap_bilinear(m, 0, (ts_vec2){3.0f / 8, 5.5f / 8}).r,
                 (tx[5 * 8 + 2] + tx[5 * 8 + 3]) / 2, 1e-7, "bilinear halfway");
    /* Across the repeat seam: between texel 7 and texel 0. */
    assert_close(ts_mipmap_bilinear(m, 0, (ts_vec2){0, 0.5f / 8}).r, (tx[7] + tx[0]) / 2, 1e-7,
                 "bilinear seam");

    /* Trilinear: level L−1+log₂ w (L = 4 levels). w = 1/8 → level 0 exactly; w = 1/4 →
     * level 1; w between → the lerp; w ≥ 1 → the 1 × 1 average; tiny → level 0. Float
     * log₂ of a power of two may miss the integer by an ulp, hence 1e-5. */
    ts_vec2 st = {0.37f, 0.61f};
    assert_close(ts_mipmap_trilinear(m, st, 1.0f / 8).r, ts_mipmap_bilinear(m, 0, st).r, 1e-5, "w = 1/8");
    assert_close(ts_mipmap_trilinear(m, st, 1.0f / 4).r, ts_mipmap_bilinear(m, 1, st).r, 1e-5, "w = 1/4");
    assert_close(ts_mipmap_trilinear(m, st, 1.0f / 2).r, ts_mipmap_bilinear(m, 2, st).r, 1e-5, "w = 1/2");
    double mid = ts_mipmap_trilinear(m, st, (float)(sqrt(2) / 8)).r;
    assert_close(mid, 0.5 * (ts_mipmap_bilinear(m, 0, st).r + ts_mipmap_bilinear(m, 1, st).r), 1e-5,
                 "w = √2/8");
    assert_true(ts_mipmap_trilinear(m, st, 1).r == ts_mipmap_texel(m, 3, 0, 0).r);
    assert_true(ts_mipmap_trilinear(m, st, 5).r == ts_mipmap_texel(m, 3, 0, 0).r);
    assert_true(ts_mipmap_trilinear(m, st, 0).r == ts_mipmap_bilinear(m, 0, st).r);
    assert_true(ts_mipmap_trilinear(m, st, NAN).r == ts_mipmap_bilinear(m, 0, st).r);
    /* Continuous at a level boundary: just below and above w = 1/4. */
    double below = ts_mipmap_trilinear(m, st, 0.25f * (1 - 1e-4f)).r,
           above = ts_mipmap_trilinear(m, st, 0.25f * (1 + 1e-4f)).r;
    assert_close(below, above, 1e-3, "continuity at a level boundary");
    /* Through the footprint: w = 2·max |component|. */
    assert_true(ts_mipmap_lookup(m, st, (ts_vec2){0.05f, -0.125f}, (ts_vec2){0.01f, 0}, true, 8).r ==
                ts_mipmap_trilinear(m, st, 0.25f).r);

    /* EWA: no footprint → bilinear at level 0; the average of any footprint of a
     * constant map is the constant; a huge one the 1 × 1 average. */
    assert_true(ts_mipmap_ewa(m, st, (ts_vec2){0, 0}, (ts_vec2){0, 0}, 8).r ==
                ts_mipmap_bilinear(m, 0, st).r);
    assert_close(ts_mipmap_ewa(m, st, (ts_vec2){10, 3}, (ts_vec2){-2, 8}, 8).r, ts_mipmap_texel(m, 3, 0, 0).r,
                 1e-6, "EWA, huge footprint");
    float kk[64];
    for (int i = 0; i < 64; i++)
        kk[i] = 0.3f;
    ts_mipmap *k = mkmap(kk, 8, 8, 1, TS_TEXTURE_WRAP_REPEAT);
    const float fp[][4] = {{0.01f, 0, 0, 0.01f},
                           {0.2f, 0.1f, -0.01f, 0.02f},
                           {0.001f, 0.3f, 0.05f, 0},
                           {0.6f, 0.6f, 0, 0.0001f}};
    for (int i = 0; i < 4; i++)
        assert_close(ts_mipmap_ewa(k, st, (ts_vec2){fp[i][0], fp[i][1]}, (ts_vec2){fp[i][2], fp[i][3]}, 8).r,
                     0.3, 1e-6, "EWA of a constant");
    ts_mipmap_destroy(k);
    /* An EWA result is a weighted mean: within the texels' range. */
    for (int i = 0; i < 4; i++) {
        float v = ts_mipmap_ewa(m, st, (ts_vec2){fp[i][0], fp[i][1]}, (ts_vec2){fp[i][2], fp[i][3]}, 8).r;
        assert_true(v >= 0 && v <= 7.0f / 8 + 0.25f);
    }
    /* Non-finite input is looked up as (0, 0) / no footprint, never NaN. */
    assert_true(ts_mipmap_ewa(m, (ts_vec2){NAN, 0}, (ts_vec2){0, 0}, (ts_vec2){0, 0}, 8).r ==
                ts_mipmap_bilinear(m, 0, (ts_vec2){0, 0}).r);
    assert_true(isfinite(ts_mipmap_ewa(m, st, (ts_vec2){INFINITY, 0}, (ts_vec2){0, 1}, 8).r));
    ts_mipmap_destroy(m);
}

/* EWA from the book's description, in double, by another route: the filter ellipse is
 * {x : xᵀ M⁻¹ x < 1} with M = J Jᵀ + I (J the footprint axes in texels), scanned over a
 * box wider than it; weights from the map's own table, by ⌊128 r²⌋. */
static double ref_ewa_level(const ts_mipmap *m, int level, ts_vec2 st, const double a0[2], const double a1[2])
{
    if (level >= m->n_levels) return ts_mipmap_texel(m, m->n_levels - 1, 0, 0).r;
    double w = m->levels[level].width, h = m->levels[level].height;
    double s = st.x * w - 0.5, t = st.y * h - 0.5;
    double ax = a0[0] * w, ay = a0[1] * h, bx = a1[0] * w, by = a1[1] * h;
    double m11 = ax * ax + bx * bx + 1, m12 = ax * ay + bx * by, m22 = ay * ay + by * by + 1;
    double det = m11 * m22 - m12 * m12;
    double r = sqrt(m11 + m22) + 2; /* ≥ the largest semi-axis, sqrt of M's largest eigenvalue */
    double sum = 0, sum_w = 0;
    for (long it = (long)floor(t - r); it <= (long)ceil(t + r); it++)
        for (long is = (long)floor(s - r); is <= (long)ceil(s + r); is++) {
            double ss = is - s, tt = it - t;
            double r2 = (m22 * ss * ss - 2 * m12 * ss * tt + m11 * tt * tt) / det;
            if (r2 < 1) {
                int idx = (int)(r2 * TS_MIPMAP_EWA_LUT_SIZE);
                if (idx > TS_MIPMAP_EWA_LUT_SIZE - 1) idx = TS_MIPMAP_EWA_LUT_SIZE - 1;
                sum += ts_mipmap_texel(m, level, is, it).r * m->ewa_weights[idx];
                sum_w += m->ewa_weights[idx];
            }
        }
    return sum / sum_w;
}

static double ref_ewa(const ts_mipmap *m, ts_vec2 st, ts_vec2 d0, ts_vec2 d1, double max_aniso)
{
    double a0[2] = {d0.x, d0.y}, a1[2] = {d1.x, d1.y};
    if (hypot(a0[0], a0[1]) < hypot(a1[0], a1[1])) {
        double t0 = a0[0], t1 = a0[1];
        a0[0] = a1[0], a0[1] = a1[1], a1[0] = t0, a1[1] = t1;
    }
    double major = hypot(a0[0], a0[1]), minor = hypot(a1[0], a1[1]);
    if (minor * max_aniso < major && minor > 0) {
        double k = major / (minor * max_aniso);
        a1[0] *= k, a1[1] *= k, minor *= k;
    }
    double lod = fmax(0, m->n_levels - 1 + log2(minor));
    int il = (int)floor(lod);
    double f = lod - il;
    return (1 - f) * ref_ewa_level(m, il, st, a0, a1) + f * ref_ewa_level(m, il + 1, st, a0, a1);
}

static void test_mipmap_ewa(void **state)
{
    (void)state;
    float tx[32 * 16];
    ts_pcg32 rng;
    ts_pcg32_seed(&rng, 11, 0);
    for (int i = 0; i < 32 * 16; i++) tx[i] = ts_pcg32_float(&rng);
    ts_mipmap *m = mkmap(tx, 32, 16, 1, TS_TEXTURE_WRAP_REPEAT);
    /* Footprints: isotropic, oblique, 4:1, beyond the 8:1 clamp, magnifying, across the
     * seam; away from integer levels of detail. Equal but for a weight-table bin flip
     * (a texel's r² within ~1e-7 of a bin edge), which none of these hits: 2e-6. */
    const float q[][6] = {
        {0.3f, 0.7f, 0.021f, 0.003f, -0.002f, 0.019f}, {0.51f, 0.22f, 0.06f, 0.05f, -0.012f, 0.014f},
        {0.9f, 0.1f, 0.09f, 0.0f, 0.0f, 0.023f},       {0.12f, 0.45f, 0.2f, 0.13f, -0.004f, 0.006f},
        {0.66f, 0.31f, 0.0035f, 0.001f, 0.0f, 0.0029f}, {0.99f, 0.01f, 0.03f, -0.04f, 0.05f, 0.037f},
    };
    for (size_t i = 0; i < sizeof q / sizeof q[0]; i++) {
        ts_vec2 st = {q[i][0], q[i][1]}, d0 = {q[i][2], q[i][3]}, d1 = {q[i][4], q[i][5]};
        char what[64];
        snprintf(what, sizeof what, "EWA footprint %zu", i);
        assert_close(ts_mipmap_ewa(m, st, d0, d1, 8).r, ref_ewa(m, st, d0, d1, 8), 2e-6, what);
    }
    ts_mipmap_destroy(m);
}

static void test_wrap_modes(void **state)
{
    (void)state;
    float tx[4] = {1, 2, 3, 4}; /* 2 × 2: row t = 0 is 1, 2 */
    ts_mipmap *rep = mkmap(tx, 2, 2, 1, TS_TEXTURE_WRAP_REPEAT);
    ts_mipmap *cla = mkmap(tx, 2, 2, 1, TS_TEXTURE_WRAP_CLAMP);
    ts_mipmap *blk = mkmap(tx, 2, 2, 1, TS_TEXTURE_WRAP_BLACK);
    /* Outside [0, 1]²: repeat is periodic, clamp takes the edge, black is 0. */
    ts_vec2 out = {1.25f, 0.25f}; /* texel (2, 0) → (0, 0) repeated, (1, 0) clamped */
    assert_true(ts_mipmap_bilinear(rep, 0, out).r == 1);
    assert_true(ts_mipmap_bilinear(cla, 0, out).r == 2);
    assert_true(ts_mipmap_bilinear(blk, 0, (ts_vec2){1.75f, 0.25f}).r == 0);
    assert_true(ts_mipmap_bilinear(blk, 0, (ts_vec2){1.0f, 0.25f}).r ==
                1); /* half of texel 2 and half of 0 */
    assert_true(ts_mipmap_texel(rep, 0, -1, -1).r == 4 && ts_mipmap_texel(cla, 0, -5, 9).r == 3 &&
                ts_mipmap_texel(blk, 0, 2, 0).r == 0);
    assert_true(ts_mipmap_bilinear(rep, 0, (ts_vec2){-0.75f, 3.25f}).r == 1);
    ts_mipmap_destroy(rep), ts_mipmap_destroy(cla), ts_mipmap_destroy(blk);
}

static void test_mipmap_refusals(void **state)
{
    (void)state;
    ts_mipmap *m = NULL;
    ts_error err = {0};
    float tx[4] = {0, 1, NAN, 3};
    assert_int_equal(ts_mipmap_create(tx, 2, 2, 1, TS_TEXTURE_WRAP_REPEAT, 0, &m, &err), TS_ERR_INVALID);
    assert_message(&err, "texel (0, 1) is nan, not a finite number within ±1e30");
    tx[2] = -2e30f;
    assert_int_equal(ts_mipmap_create(tx, 2, 2, 1, TS_TEXTURE_WRAP_REPEAT, 0, &m, &err), TS_ERR_INVALID);
    assert_message(&err, "texel (0, 1) is -2e+30, not a finite number within ±1e30");
    assert_null(m);
    assert_int_equal(ts_mipmap_create(tx, 0, 2, 1, TS_TEXTURE_WRAP_REPEAT, 0, &m, &err), TS_ERR_INVALID);
    assert_message(&err, "the image is empty (0 × 2 texels)");
    tx[2] = 2;
    assert_int_equal(ts_mipmap_create(tx, 2, 2, 1, TS_TEXTURE_WRAP_REPEAT, 16, &m, &err), TS_ERR_LIMIT);
    assert_message(&err, "the MIP map of a 2 × 2 image needs 20 bytes, more than the 16 left");
    assert_int_equal(ts_mipmap_create(tx, 2, 2, 2, TS_TEXTURE_WRAP_REPEAT, 0, &m, &err), TS_ERR_INVALID);
    assert_message(&err, "a MIP map has 1 or 3 channels, not 2");
}

/* ---------------------------------------------------------- image files ---- */

/* A PNG written with libpng: w × h, the given colour type and bit depth, from raw rows
 * (already in the file's sample layout). */
static void write_png(const char *rel, int w, int h, int color_type, int bit_depth, int interlace,
                      const unsigned char *rows, size_t rowbytes, const png_color *palette, int n_palette)
{
    char path[512];
    snprintf(path, sizeof path, "%s/%s", ts_tmp_dir, rel);
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
    png_infop info = png_create_info_struct(png);
    assert_non_null(png), assert_non_null(info);
    if (setjmp(png_jmpbuf(png))) fail_msg("libpng failed writing %s", rel);
    png_init_io(png, f);
    png_set_IHDR(png, info, (png_uint_32)w, (png_uint_32)h, bit_depth, color_type, interlace,
                 PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    if (palette) png_set_PLTE(png, info, palette, n_palette);
    png_write_info(png, info);
    int passes = png_set_interlace_handling(png);
    for (int p = 0; p < passes; p++)
        for (int y = 0; y < h; y++)
            png_write_row(png, rows + (size_t)y * rowbytes);
    png_write_end(png, info);
    png_destroy_write_struct(&png, &info);
    assert_int_equal(fclose(f), 0);
}

static const ts_mipmap *cache_get(ts_texture_cache *c, const char *file, int nc, bool gamma, float scale,
                                  ts_texture_wrap wrap)
{
    ts_texture_image_options opt = {.n_channels = nc, .gamma = gamma, .scale = scale, .wrap = wrap};
    const ts_mipmap *m = NULL;
    ts_error err = {0};
    if (ts_texture_cache_get(c, ts_tmp_dir, file, 0, &opt, &m, &err)) fail_msg("%s: %s", file, err.message);
    return m;
}

/* Texel (x, y) of the image as a viewer shows it (y from the top) in level 0 of a map
 * built from an image of height h (t = 0 is the bottom row). */
static ts_rgb image_texel(const ts_mipmap *m, int x, int y, int h)
{
    return ts_mipmap_texel(m, 0, x, h - 1 - y);
}

static void test_png(void **state)
{
    (void)state;
    ts_texture_cache *cache = ts_texture_cache_create(0);
    assert_non_null(cache);
    /* 8-bit RGB, 2 × 2 (a power of two, so level 0 holds the texels unresampled). */
    const unsigned char rgb8[2][6] = {{10, 20, 30, 188, 0, 255}, {255, 128, 1, 0, 0, 0}};
    write_png("rgb8.png", 2, 2, PNG_COLOR_TYPE_RGB, 8, PNG_INTERLACE_NONE, &rgb8[0][0], 6, NULL, 0);
    const ts_mipmap *m = cache_get(cache, "rgb8.png", 3, false, 1, TS_TEXTURE_WRAP_REPEAT);
    assert_rgb(image_texel(m, 0, 0, 2), 10 / 255.f, 20 / 255.f, 30 / 255.f, 0, "png (0, 0)");
    assert_rgb(image_texel(m, 1, 0, 2), 188 / 255.f, 0, 1, 0, "png (1, 0)");
    assert_rgb(image_texel(m, 0, 1, 2), 1, 128 / 255.f, 1 / 255.f, 0, "png (0, 1), the bottom row: t = 0");
    assert_true(ts_mipmap_texel(m, 0, 0, 0).r == 1); /* t = 0 is the image's bottom row */
    /* gamma: the sRGB decoding of the codes; 188 is ≈ 0.5 linear. */
    m = cache_get(cache, "rgb8.png", 3, true, 2, TS_TEXTURE_WRAP_REPEAT);
    double lin188 = pow((188 / 255.0 + 0.055) / 1.055, 2.4);
    assert_close(image_texel(m, 1, 0, 2).r, 2 * lin188, 1e-6, "gamma + scale");
    assert_close(lin188, 0.5029, 1e-4, "code 188");
    assert_close(image_texel(m, 0, 0, 2).r, 2 * (10 / 255.0) / 12.92, 1e-7, "gamma, linear segment");
    /* A float texture: luminance of the codes, then gamma. */
    m = cache_get(cache, "rgb8.png", 1, true, 1, TS_TEXTURE_WRAP_REPEAT);
    double y = 0.212671 * 255 / 255 + 0.715160 * 128 / 255 + 0.072169 * 1 / 255;
    assert_close(image_texel(m, 0, 1, 2).r, pow((y + 0.055) / 1.055, 2.4), 1e-6,
                 "float texture: y then gamma");
    assert_int_equal(ts_texture_cache_count(cache), 3);
    /* The same file and options again: the cached map. */
    assert_ptr_equal(cache_get(cache, "rgb8.png", 1, true, 1, TS_TEXTURE_WRAP_REPEAT), m);
    assert_ptr_equal(cache_get(cache, "./rgb8.png", 1, true, 1, TS_TEXTURE_WRAP_REPEAT), m);
    assert_int_equal(ts_texture_cache_count(cache), 3);

    /* 16-bit grey + alpha, interlaced: the high byte of the grey, alpha dropped. */
    unsigned char ga16[4][4 * 4];
    for (int yy = 0; yy < 4; yy++)
        for (int x = 0; x < 4; x++) {
            unsigned g = (unsigned)(yy * 4 + x) * 4000 + 77, a = 65535 - (unsigned)x;
            unsigned char *p = &ga16[yy][x * 4];
            p[0] = (unsigned char)(g >> 8), p[1] = (unsigned char)g, p[2] = (unsigned char)(a >> 8),
            p[3] = (unsigned char)a;
        }
    write_png("ga16.png", 4, 4, PNG_COLOR_TYPE_GRAY_ALPHA, 16, PNG_INTERLACE_ADAM7, &ga16[0][0], 16, NULL, 0);
    m = cache_get(cache, "ga16.png", 3, false, 1, TS_TEXTURE_WRAP_REPEAT);
    for (int yy = 0; yy < 4; yy++)
        for (int x = 0; x < 4; x++) {
            float want = (float)(((yy * 4 + x) * 4000 + 77) >> 8) / 255.f;
            assert_rgb(image_texel(m, x, yy, 4), want, want, want, 0, "16-bit grey");
        }
    /* A palette image with 4-bit indices. */
    png_color pal[3] = {{255, 0, 0}, {0, 255, 0}, {1, 2, 3}};
    unsigned char idx[2][1] = {{0x12}, {0x20}}; /* rows: [1, 2], [2, 0] */
    write_png("pal.png", 2, 2, PNG_COLOR_TYPE_PALETTE, 4, PNG_INTERLACE_NONE, &idx[0][0], 1, pal, 3);
    m = cache_get(cache, "pal.png", 3, false, 1, TS_TEXTURE_WRAP_REPEAT);
    assert_rgb(image_texel(m, 0, 0, 2), 0, 1, 0, 0, "palette (0, 0)");
    assert_rgb(image_texel(m, 1, 0, 2), 1 / 255.f, 2 / 255.f, 3 / 255.f, 0, "palette (1, 0)");
    assert_rgb(image_texel(m, 1, 1, 2), 1, 0, 0, 0, "palette (1, 1)");
    /* 1-bit grey. */
    unsigned char bits[2][1] = {{0x80}, {0x40}};
    write_png("bw.png", 2, 2, PNG_COLOR_TYPE_GRAY, 1, PNG_INTERLACE_NONE, &bits[0][0], 1, NULL, 0);
    m = cache_get(cache, "bw.png", 3, false, 1, TS_TEXTURE_WRAP_REPEAT);
    assert_true(image_texel(m, 0, 0, 2).g == 1 && image_texel(m, 1, 0, 2).g == 0 &&
                image_texel(m, 1, 1, 2).b == 1);

    /* ts_png_encode's output (what tessera writes) reads back to its 8-bit codes. */
    ts_image img = {0};
    ts_error err = {0};
    const char *names[3] = {"R", "G", "B"};
    assert_int_equal(ts_image_init(&img, 3, 1, 3, names, &err), TS_OK);
    for (int i = 0; i < 9; i++)
        img.data[i] = (float)i / 8;
    unsigned char *buf = NULL;
    size_t len = 0;
    assert_int_equal(ts_png_encode(&img, 0, &buf, &len, &err), TS_OK);
    ts_image back = {0};
    assert_int_equal(ts_png_decode(buf, len, "encoded", &back, &err), TS_OK);
    for (int i = 0; i < 9; i++)
        assert_true(back.data[i] == (float)ts_srgb8_from_linear(img.data[i]) / 255.f);
    free(buf);
    ts_image_fini(&img), ts_image_fini(&back);
    ts_texture_cache_destroy(cache);
}

static void test_exr(void **state)
{
    (void)state;
    ts_texture_cache *cache = ts_texture_cache_create(0);
    ts_image img = {0};
    ts_error err = {0};
    const char *names[3] = {"R", "G", "B"};
    assert_int_equal(ts_image_init(&img, 2, 3, 3, names, &err), TS_OK);
    for (int i = 0; i < 18; i++)
        img.data[i] = (float)i * 0.37f - 1; /* negative values are kept */
    char path[512];
    snprintf(path, sizeof path, "%s/rgb.exr", ts_tmp_dir);
    assert_int_equal(ts_exr_write(path, &img, &err), TS_OK);
    /* 2 × 3 is resampled to 2 × 4; read it flat (no gamma by default for EXR) and check
     * against a map made here from the same texels, flipped. */
    assert_false(ts_texture_image_default_gamma("rgb.exr"));
    const ts_mipmap *m = cache_get(cache, "rgb.exr", 3, false, 1, TS_TEXTURE_WRAP_CLAMP);
    float flipped[18];
    for (int y = 0; y < 3; y++)
        memcpy(flipped + (2 - y) * 6, img.data + y * 6, 6 * sizeof(float));
    ts_mipmap *want = mkmap(flipped, 2, 3, 3, TS_TEXTURE_WRAP_CLAMP);
    for (int t = 0; t < 4; t++)
        for (int s = 0; s < 2; s++) {
            ts_rgb a = ts_mipmap_texel(m, 0, s, t), b = ts_mipmap_texel(want, 0, s, t);
            assert_true(a.r == b.r && a.g == b.g && a.b == b.b);
        }
    ts_mipmap_destroy(want);
    ts_image_fini(&img);
    /* A Y-only file is grey. */
    const char *yname[1] = {"Y"};
    assert_int_equal(ts_image_init(&img, 1, 1, 1, yname, &err), TS_OK);
    img.data[0] = 0.25f;
    snprintf(path, sizeof path, "%s/y.exr", ts_tmp_dir);
    assert_int_equal(ts_exr_write(path, &img, &err), TS_OK);
    ts_image_fini(&img);
    m = cache_get(cache, "y.exr", 3, false, 1, TS_TEXTURE_WRAP_REPEAT);
    assert_rgb(ts_mipmap_texel(m, 0, 0, 0), 0.25, 0.25, 0.25, 0, "Y");
    /* Only G: R and B are 0, as OpenEXR's RGBA interface fills them. */
    const char *gname[1] = {"G"};
    assert_int_equal(ts_image_init(&img, 1, 1, 1, gname, &err), TS_OK);
    img.data[0] = 0.5f;
    snprintf(path, sizeof path, "%s/g.exr", ts_tmp_dir);
    assert_int_equal(ts_exr_write(path, &img, &err), TS_OK);
    ts_image_fini(&img);
    m = cache_get(cache, "g.exr", 3, false, 1, TS_TEXTURE_WRAP_REPEAT);
    assert_rgb(ts_mipmap_texel(m, 0, 0, 0), 0, 0.5, 0, 0, "G only");
    ts_texture_cache_destroy(cache);
}

static void put_f32(unsigned char *p, float f, int little)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    for (int i = 0; i < 4; i++)
        p[little ? i : 3 - i] = (unsigned char)(u >> (8 * i));
}

/* A PFM of w × h from values given top row first; rows are stored bottom first. */
static size_t make_pfm(unsigned char *out, int nc, int w, int h, const char *scale, const float *values)
{
    int little = scale[0] == '-';
    size_t n = (size_t)sprintf((char *)out, "%s\n%d %d\n%s\n", nc == 3 ? "PF" : "Pf", w, h, scale);
    for (int row = h - 1; row >= 0; row--)
        for (int i = 0; i < w * nc; i++, n += 4)
            put_f32(out + n, values[row * w * nc + i], little);
    return n;
}

static void test_pfm(void **state)
{
    (void)state;
    ts_texture_cache *cache = ts_texture_cache_create(0);
    unsigned char buf[512];
    const float v[2 * 2 * 3] = {0.5f, 1.5f, -2, 3, 4, 5, 6.25f, 7, 8, 9, 10, 1e-3f}; /* top row first */
    size_t n = make_pfm(buf, 3, 2, 2, "-1.0", v);
    write_bytes("le.pfm", buf, n);
    const ts_mipmap *m = cache_get(cache, "le.pfm", 3, false, 1, TS_TEXTURE_WRAP_REPEAT);
    assert_rgb(image_texel(m, 0, 0, 2), 0.5, 1.5, -2, 0, "pfm (0, 0)");
    assert_rgb(image_texel(m, 1, 1, 2), 9, 10, 1e-3f, 0, "pfm (1, 1)");
    /* Big-endian with a scale of 2: values doubled (pbrt-v3 multiplies by |scale|). */
    n = make_pfm(buf, 3, 2, 2, "2", v);
    write_bytes("be.pfm", buf, n);
    m = cache_get(cache, "be.pfm", 3, false, 1, TS_TEXTURE_WRAP_REPEAT);
    assert_rgb(image_texel(m, 1, 0, 2), 6, 8, 10, 0, "pfm big-endian, scale 2");
    /* Grey, 3 × 1 (resampled: compare level 0 with a map of the same texels). */
    const float g[3] = {0.25f, 0.5f, 0.75f};
    n = make_pfm(buf, 1, 3, 1, "-1", g);
    write_bytes("grey.pfm", buf, n);
    m = cache_get(cache, "grey.pfm", 1, false, 1, TS_TEXTURE_WRAP_REPEAT);
    float lum[3];
    for (int i = 0; i < 3; i++)
        lum[i] = 0.212671f * g[i] + 0.715160f * g[i] + 0.072169f * g[i];
    ts_mipmap *want = mkmap(lum, 3, 1, 1, TS_TEXTURE_WRAP_REPEAT);
    for (int s = 0; s < 4; s++)
        assert_true(ts_mipmap_texel(m, 0, s, 0).r == ts_mipmap_texel(want, 0, s, 0).r);
    ts_mipmap_destroy(want);
    /* Header whitespace of any kind between fields; trailing bytes are ignored. */
    const char *hdr = "PF \r\n 1\t1 \n-1\n";
    size_t hn = strlen(hdr);
    memcpy(buf, hdr, hn);
    put_f32(buf + hn, 1, 1), put_f32(buf + hn + 4, 2, 1), put_f32(buf + hn + 8, 3, 1);
    memcpy(buf + hn + 12, "extra", 5);
    ts_image img = {0};
    ts_error err = {0};
    assert_int_equal(ts_pfm_decode(buf, hn + 17, "x.pfm", &img, &err), TS_OK);
    assert_true(img.width == 1 && img.data[0] == 1 && img.data[2] == 3);
    ts_image_fini(&img);
    ts_texture_cache_destroy(cache);
}

static size_t tga_header(unsigned char *h, int type, int cmap, int first, int cmap_len, int cmap_bits, int w,
                         int hgt, int depth, int desc)
{
    memset(h, 0, 18);
    h[1] = (unsigned char)cmap, h[2] = (unsigned char)type;
    h[3] = (unsigned char)first, h[4] = (unsigned char)(first >> 8);
    h[5] = (unsigned char)cmap_len, h[6] = (unsigned char)(cmap_len >> 8), h[7] = (unsigned char)cmap_bits;
    h[12] = (unsigned char)w, h[13] = (unsigned char)(w >> 8), h[14] = (unsigned char)hgt,
    h[15] = (unsigned char)(hgt >> 8);
    h[16] = (unsigned char)depth, h[17] = (unsigned char)desc;
    return 18;
}

static void test_tga(void **state)
{
    (void)state;
    unsigned char b[256];
    ts_image img = {0};
    ts_error err = {0};
    /* Type 2, 24-bit BGR, bottom-up (descriptor 0): file row 0 is the image's bottom. */
    size_t n = tga_header(b, 2, 0, 0, 0, 0, 2, 2, 24, 0);
    const unsigned char px[12] = {30, 20, 10, 0,   0,   255,  /* bottom: (10,20,30), (255,0,0) */
                                  1,  2,  3,  255, 255, 255}; /* top: (3,2,1), white */
    memcpy(b + n, px, 12);
    assert_int_equal(ts_tga_decode(b, n + 12, "a.tga", &img, &err), TS_OK);
    assert_true(img.data[0] == 3 / 255.f && img.data[2] == 1 / 255.f); /* top-left */
    assert_true(img.data[6] == 10 / 255.f && img.data[8] == 30 / 255.f &&
                img.data[9] == 1); /* bottom-left, right */
    ts_image_fini(&img);
    /* Top-down and right-to-left (descriptor bits 5 and 4). */
    b[17] = 0x30;
    assert_int_equal(ts_tga_decode(b, n + 12, "a.tga", &img, &err), TS_OK);
    assert_true(img.data[0] == 1 && img.data[1] == 0 &&
                img.data[3] == 10 / 255.f); /* file pixel 1 at x = 0 */
    ts_image_fini(&img);
    /* Type 10 (RLE), 32-bit BGRA, top-down: a repeat packet of 3 and a raw packet of 1. */
    n = tga_header(b, 10, 0, 0, 0, 0, 2, 2, 32, 0x28);
    const unsigned char rle[] = {0x82, 50, 60, 70, 9, 0x00, 1, 2, 3, 4};
    memcpy(b + n, rle, sizeof rle);
    write_bytes("rle.tga", b, n + sizeof rle);
    assert_int_equal(ts_tga_decode(b, n + sizeof rle, "rle.tga", &img, &err), TS_OK);
    assert_true(img.data[0] == 70 / 255.f && img.data[6] == 70 / 255.f && img.data[9] == 3 / 255.f &&
                img.data[11] == 1 / 255.f);
    ts_image_fini(&img);
    /* Through the cache with the default gamma of .tga (true). */
    assert_true(ts_texture_image_default_gamma("RLE.TGA"));
    ts_texture_cache *cache = ts_texture_cache_create(0);
    const ts_mipmap *m = cache_get(cache, "rle.tga", 3, true, 1, TS_TEXTURE_WRAP_REPEAT);
    assert_close(image_texel(m, 1, 1, 2).b, (1 / 255.0) / 12.92, 1e-9, "tga gamma");
    ts_texture_cache_destroy(cache);
    /* Type 3, 8-bit grey; type 11 (RLE grey). */
    n = tga_header(b, 3, 0, 0, 0, 0, 2, 1, 8, 0);
    b[n] = 0, b[n + 1] = 255;
    assert_int_equal(ts_tga_decode(b, n + 2, "g.tga", &img, &err), TS_OK);
    assert_true(img.data[0] == 0 && img.data[3] == 1 && img.data[5] == 1);
    ts_image_fini(&img);
    n = tga_header(b, 11, 0, 0, 0, 0, 3, 1, 8, 0);
    b[n] = 0x82, b[n + 1] = 51;
    assert_int_equal(ts_tga_decode(b, n + 2, "g.tga", &img, &err), TS_OK);
    assert_true(img.data[0] == 0.2f && img.data[8] == 0.2f);
    ts_image_fini(&img);
    /* Type 1: 8-bit indices into a 24-bit map starting at entry 5; 16-bit 5-5-5. */
    n = tga_header(b, 1, 1, 5, 2, 24, 2, 1, 8, 0);
    const unsigned char map_px[] = {0, 0, 255, 255, 0, 0, 6, 5};
    memcpy(b + n, map_px, sizeof map_px);
    assert_int_equal(ts_tga_decode(b, n + sizeof map_px, "c.tga", &img, &err), TS_OK);
    assert_true(img.data[2] == 1 && img.data[0] == 0 && img.data[3] == 1 && img.data[5] == 0);
    ts_image_fini(&img);
    n = tga_header(b, 2, 0, 0, 0, 0, 1, 1, 16, 0);
    b[n] = 0x1f, b[n + 1] = 0x7c; /* r = 31, g = 0, b = 31 */
    assert_int_equal(ts_tga_decode(b, n + 2, "h.tga", &img, &err), TS_OK);
    assert_true(img.data[0] == 1 && img.data[1] == 0 && img.data[2] == 1);
    ts_image_fini(&img);
}

/* ------------------------------------------------------------- refusals ---- */

/* The CRC-32 of PNG chunks (ISO 3309), bit by bit. */
static uint32_t crc32_of(const unsigned char *p, size_t n)
{
    uint32_t c = 0xffffffffu;
    for (size_t i = 0; i < n; i++) {
        c ^= p[i];
        for (int k = 0; k < 8; k++)
            c = (c >> 1) ^ (0xedb88320u & (0u - (c & 1)));
    }
    return c ^ 0xffffffffu;
}

static void test_decoder_refusals(void **state)
{
    (void)state;
    unsigned char tga[64];
    ts_image img = {0};
    ts_error err = {0};
    size_t n = tga_header(tga, 2, 0, 0, 0, 0, 2, 2, 24, 0);
    memset(tga + n, 7, 11);
    struct {
        int fmt; /* 0 tga, 1 pfm, 2 png */
        const void *bytes;
        size_t len;
        ts_status st;
        const char *msg;
    } cases[] = {
        {0, tga, n + 11, TS_ERR_INVALID, "t.tga: the file is truncated (11 bytes of pixels, 12 expected)"},
        {0, tga, 10, TS_ERR_INVALID, "t.tga: 10 bytes are too few for a TGA header"},
        {1, "PF\n2 2\n-1\n", 10, TS_ERR_INVALID,
         "t.pfm: the file is truncated (0 bytes of pixels, 48 expected)"},
        {1, "PF\n0 4\n-1\n", 10, TS_ERR_INVALID, "t.pfm: the image has a zero size (0 × 4)"},
        {1, "PF\n2 x\n-1\n", 10, TS_ERR_INVALID, "t.pfm: the PFM header has no valid height"},
        {1, "PF\n2 2\n0\n", 9, TS_ERR_INVALID, "t.pfm: the PFM scale \"0\" is not a finite non-zero number"},
        {1, "PF\n2 2\n-1", 9, TS_ERR_INVALID, "t.pfm: the PFM file ends after its header"},
        {1, "P6\n2 2\n255\n", 11, TS_ERR_INVALID,
         "t.pfm: not a PFM file (it does not start with \"PF\" or \"Pf\")"},
        {1, "PF\n20000 20000\n-1\n", 19, TS_ERR_LIMIT,
         "t.pfm: the image is 20000 × 20000 pixels, more than the limit of 268435456"},
        {2, "\x89PNG\r\n\x1a\n", 8, TS_ERR_INVALID,
         "t.png: the PNG file is corrupt or truncated (libpng: the file is truncated)"},
        {2, "GIF89a....", 10, TS_ERR_INVALID, "t.png: not a PNG file (no PNG signature)"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        ts_status st = cases[i].fmt == 0   ? ts_tga_decode(cases[i].bytes, cases[i].len, "t.tga", &img, &err)
                       : cases[i].fmt == 1 ? ts_pfm_decode(cases[i].bytes, cases[i].len, "t.pfm", &img, &err)
                                           : ts_png_decode(cases[i].bytes, cases[i].len, "t.png", &img, &err);
        assert_int_equal(st, cases[i].st);
        assert_message(&err, cases[i].msg);
        assert_null(img.data);
    }
    /* TGA specifics. */
    n = tga_header(tga, 10, 0, 0, 0, 0, 2, 1, 24, 0);
    tga[n] = 0x82; /* a run of 3 in a 2-pixel image */
    memset(tga + n + 1, 0, 3);
    assert_int_equal(ts_tga_decode(tga, n + 4, "t.tga", &img, &err), TS_ERR_INVALID);
    assert_message(&err, "t.tga: a run-length packet runs past the image's last pixel");
    n = tga_header(tga, 10, 0, 0, 0, 0, 2, 1, 24, 0);
    tga[n] = 0x00, tga[n + 1] = 1, tga[n + 2] = 2, tga[n + 3] = 3; /* raw 1, then nothing */
    assert_int_equal(ts_tga_decode(tga, n + 4, "t.tga", &img, &err), TS_ERR_INVALID);
    assert_message(&err, "t.tga: the file is truncated (its run-length data ends at pixel 1 of 2)");
    n = tga_header(tga, 1, 1, 0, 1, 24, 1, 1, 8, 0);
    tga[n] = 1, tga[n + 1] = 2, tga[n + 2] = 3, tga[n + 3] = 4; /* index 4, one entry */
    assert_int_equal(ts_tga_decode(tga, n + 4, "t.tga", &img, &err), TS_ERR_INVALID);
    assert_message(&err, "t.tga: colour index 4 is outside the colour map (entries 0 … 0)");
    n = tga_header(tga, 2, 0, 0, 0, 0, 0, 1, 24, 0);
    assert_int_equal(ts_tga_decode(tga, n, "t.tga", &img, &err), TS_ERR_INVALID);
    assert_message(&err, "t.tga: the image has a zero size (0 × 1)");
    n = tga_header(tga, 2, 0, 0, 0, 0, 1, 1, 12, 0);
    assert_int_equal(ts_tga_decode(tga, n + 2, "t.tga", &img, &err), TS_ERR_UNSUPPORTED);
    assert_message(&err, "t.tga: 12-bit pixels are not supported for TGA image type 2");
    n = tga_header(tga, 32, 0, 0, 0, 0, 1, 1, 24, 0);
    assert_int_equal(ts_tga_decode(tga, n + 3, "t.tga", &img, &err), TS_ERR_UNSUPPORTED);
    assert_message(&err, "t.tga: TGA image type 32 is not supported (1, 2, 3, 9, 10, 11 are)");
    /* A PNG whose header promises far more pixels than its bytes can inflate to. */
    unsigned char png[256];
    ts_image tiny = {0};
    const char *names[3] = {"R", "G", "B"};
    assert_int_equal(ts_image_init(&tiny, 1, 1, 3, names, &err), TS_OK);
    unsigned char *enc = NULL;
    size_t enc_len = 0;
    assert_int_equal(ts_png_encode(&tiny, 0, &enc, &enc_len, &err), TS_OK);
    ts_image_fini(&tiny);
    assert_true(enc_len <= sizeof png);
    memcpy(png, enc, enc_len);
    free(enc);
    /* IHDR: width at bytes 16-19, height 20-23, then its CRC (bytes 29-32). */
    png[16] = 0, png[17] = 0, png[18] = 0x40, png[19] = 0; /* 16384 wide */
    png[20] = 0, png[21] = 0, png[22] = 0x40, png[23] = 0;
    uint32_t crc = crc32_of(png + 12, 17);
    png[29] = (unsigned char)(crc >> 24), png[30] = (unsigned char)(crc >> 16),
    png[31] = (unsigned char)(crc >> 8), png[32] = (unsigned char)crc;
    assert_int_equal(ts_png_decode(png, enc_len, "t.png", &img, &err), TS_ERR_INVALID);
    char want[256];
    snprintf(want, sizeof want,
             "t.png: the PNG header promises 16384 × 16384 pixels (805322752 bytes of scanlines), more than "
             "its %zu "
             "bytes can hold",
             enc_len);
    assert_message(&err, want);
}

/* -------------------------------------------------- pbrt-v3 scene text ---- */

typedef struct built {
    ts_pbrt_scene *scene;
    ts_texture_cache *cache;
    ts_arena arena;
    ts_texture_pbrt tp;
} built;

static ts_status build(const char *body, built *b, ts_error *err)
{
    char text[4096];
    snprintf(text, sizeof text, "WorldBegin\n%sWorldEnd\n", body);
    memset(b, 0, sizeof *b);
    ts_arena_init(&b->arena, 0);
    b->cache = ts_texture_cache_create(0);
    ts_status st = ts_pbrt_parse_text(text, strlen(text), "t.pbrt", ts_tmp_dir, NULL, &b->scene, err);
    if (st) return st;
    return ts_texture_pbrt_build(&b->tp, b->scene, &b->arena, b->cache, ts_tmp_dir, 0, err);
}

static void unbuild(built *b)
{
    ts_pbrt_scene_destroy(b->scene);
    ts_texture_cache_destroy(b->cache);
    ts_arena_fini(&b->arena);
}

static const ts_texture *named(const built *b, const char *name)
{
    for (size_t i = 0; i < b->scene->texture_count; i++)
        if (strcmp(b->scene->textures[i].name, name) == 0) return b->tp.textures[i];
    fail_msg("no texture %s", name);
    return NULL;
}

static void test_pbrt_textures(void **state)
{
    (void)state;
    /* A 4 × 4 PNG for the image texture. */
    unsigned char px[4][12];
    for (int y = 0; y < 4; y++)
        for (int x = 0; x < 12; x++)
            px[y][x] = (unsigned char)(y * 60 + x * 5);
    write_png("tex.png", 4, 4, PNG_COLOR_TYPE_RGB, 8, PNG_INTERLACE_NONE, &px[0][0], 12, NULL, 0);
    built b;
    ts_error err = {0};
    ts_status st =
        build("Texture \"k\" \"float\" \"constant\" \"float value\" 0.25\n"
              "Texture \"c\" \"color\" \"constant\" \"rgb value\" [0.1 0.2 0.3]\n"
              "Texture \"s\" \"color\" \"scale\" \"texture tex1\" \"c\" \"rgb tex2\" [2 2 2]\n"
              "Texture \"m\" \"float\" \"mix\" \"float tex1\" 1 \"float tex2\" 3 \"texture amount\" \"k\"\n"
              "Texture \"cb\" \"float\" \"checkerboard\" \"float uscale\" 2 \"float vscale\" 2\n"
              "Texture \"cb3\" \"float\" \"checkerboard\" \"integer dimension\" 3\n"
              "AttributeBegin\nScale 4 4 4\n"
              "Texture \"f\" \"float\" \"fbm\" \"integer octaves\" 5\n"
              "AttributeEnd\n"
              "Texture \"img\" \"color\" \"imagemap\" \"string filename\" \"tex.png\" \"bool trilinear\" "
              "\"true\" \"float udelta\" 0.125\n"
              "Texture \"imgf\" \"float\" \"imagemap\" \"string filename\" \"tex.png\" \"bool gamma\" "
              "\"false\" \"string wrap\" \"clamp\" \"bool invert\" \"true\"\n"
              "Texture \"uvt\" \"color\" \"uv\" \"string mapping\" \"planar\" \"vector v1\" [0 0 1]\n",
              &b, &err);
    if (st) fail_msg("%s", err.message);
    ts_texture_context c = ctx_uv(0.3f, 0.6f);
    assert_true(ts_texture_eval_float(named(&b, "k"), &c) == 0.25f);
    assert_rgb(ts_texture_eval_rgb(named(&b, "s"), &c), 0.2, 0.4, 0.6, 1e-7, "scale");
    assert_true(ts_texture_eval_float(named(&b, "m"), &c) == 0.75f * 1 + 0.25f * 3);
    /* uscale 2: (0.6, 1.2): cells 0 + 1, odd: tex2 = 0. */
    assert_true(ts_texture_eval_float(named(&b, "cb"), &c) == 0);
    ts_texture_context cp = ctx_p(0.5f, 0.5f, 1.5f);
    assert_true(ts_texture_eval_float(named(&b, "cb3"), &cp) == 0);
    /* The solid texture sees p through the CTM itself (pbrt-v3): 4·p. */
    cp = ctx_p(0.3f, 0.2f, 0.1f);
    ts_vec3 zero = {0, 0, 0};
    assert_close(ts_texture_eval_float(named(&b, "f"), &cp),
                 ts_noise_fbm((ts_vec3){1.2f, 0.8f, 0.4f}, zero, zero, 0.5f, 5), 1e-6, "fbm through Scale 4");
    /* The image: uv mapping with udelta, trilinear, no footprint → bilinear at level 0;
     * gamma by default for .png. */
    const ts_texture *img = named(&b, "img");
    assert_int_equal(img->type, TS_TEXTURE_IMAGEMAP);
    assert_true(img->image.trilinear && img->image.max_anisotropy == 8 && !img->image.invert);
    ts_rgb v = ts_texture_eval_rgb(img, &c);
    ts_rgb want = ts_mipmap_bilinear(img->image.mipmap, 0, (ts_vec2){0.425f, 0.6f});
    assert_rgb(v, want.r, want.g, want.b, 0, "imagemap");
    /* texel (1, 1) from the bottom: image row 2, pixel 1 (bytes 3 … 5 of the row): codes
     * 135, 140, 145, decoded. */
    ts_rgb t11 = ts_mipmap_texel(img->image.mipmap, 0, 1, 1);
    assert_close(t11.g, pow((140 / 255.0 + 0.055) / 1.055, 2.4), 1e-6, "decoded texel");
    const ts_texture *imgf = named(&b, "imgf");
    assert_int_equal(imgf->image.mipmap->wrap, TS_TEXTURE_WRAP_CLAMP);
    float y = 0.212671f * 135 / 255.f + 0.715160f * 140 / 255.f + 0.072169f * 145 / 255.f;
    assert_close(ts_mipmap_texel(imgf->image.mipmap, 0, 1, 1).r, y, 1e-6, "float image: luminance, no gamma");
    ts_texture_context cc = ctx_uv(1.5f / 4, 1.5f / 4); /* the centre of texel (1, 1) */
    assert_close(ts_texture_eval_float(imgf, &cc), 1 - y, 1e-6, "invert");
    /* Planar mapping onto (z, y): uv (frac z, frac y). */
    cp = ctx_p(7, 2.25f, 1.5f);
    assert_rgb(ts_texture_eval_rgb(named(&b, "uvt"), &cp), 0.5, 0.25, 0, 1e-6, "uv, planar");
    assert_int_equal(ts_texture_cache_count(b.cache), 2);

    /* Material-side lookups: a named texture, a value, the default. */
    ts_pbrt_params ps = b.scene->textures[0].params; /* any list: none of these names is in it */
    const ts_texture *t = NULL;
    assert_int_equal(ts_texture_pbrt_float(&b.tp, &ps, "roughness", 0.1f, &t, &err), TS_OK);
    assert_true(ts_texture_eval_float(t, &c) == 0.1f);
    assert_int_equal(
        ts_texture_pbrt_rgb(&b.tp, &b.scene->textures[2].params, "tex1", ts_rgb_gray(0), &t, &err), TS_OK);
    assert_ptr_equal(t, named(&b, "c"));
    /* Every parameter the textures looked up is marked used. */
    for (size_t i = 0; i < b.scene->texture_count; i++) {
        size_t cur = 0;
        const ts_pbrt_param *un = ts_pbrt_params_next_unused(&b.scene->textures[i].params, &cur);
        if (un) fail_msg("texture %s: parameter %s unused", b.scene->textures[i].name, un->name);
    }
    unbuild(&b);
}

/* pbrt-v3's dots paint the dots with "outside" (its CreateDots*Texture pass "inside" where
 * DotsTexture takes its outside texture): a .pbrt file's dots texture is made that way,
 * for colour and float textures alike. */
static void test_pbrt_dots_swapped(void **state)
{
    (void)state;
    built b;
    ts_error err = {0};
    ts_status st = build("Texture \"d\" \"color\" \"dots\" \"rgb inside\" [1 0 0] \"rgb outside\" [0 0 1]\n"
                         "Texture \"df\" \"float\" \"dots\" \"float inside\" 0.25 \"float outside\" 0.75\n"
                         "Texture \"dd\" \"float\" \"dots\"\n",
                         &b, &err);
    if (st) fail_msg("%s", err.message);
    const ts_texture *d = named(&b, "d"), *df = named(&b, "df"), *dd = named(&b, "dd");
    ts_texture_context c = ctx_uv(0.3f, 0.6f);
    assert_rgb(ts_texture_eval_rgb(d->dots.inside, &c), 0, 0, 1, 0, "dots: the dots are \"outside\"");
    assert_rgb(ts_texture_eval_rgb(d->dots.outside, &c), 1, 0, 0, 0, "dots: the rest is \"inside\"");
    assert_true(ts_texture_eval_float(df->dots.inside, &c) == 0.75f);
    assert_true(ts_texture_eval_float(df->dots.outside, &c) == 0.25f);
    /* The defaults (inside 1, outside 0) swap with them: dots of 0 on 1. */
    assert_true(ts_texture_eval_float(dd->dots.inside, &c) == 0 && ts_texture_eval_float(dd->dots.outside, &c) == 1);
    unbuild(&b);
}

static void test_pbrt_refusals(void **state)
{
    (void)state;
    write_bytes("zero.pfm", "PF\n0 4\n-1\n", 10);
    write_bytes("pic.jpg", "\xff\xd8\xff", 3);
    unsigned char nan_pfm[64];
    const float nanv[3] = {1, NAN, 0};
    write_bytes("nan.pfm", nan_pfm, make_pfm(nan_pfm, 3, 1, 1, "-1", nanv));
    struct {
        const char *body;
        ts_status st;
        const char *msg;
    } cases[] = {
        {"Texture \"p\" \"color\" \"ptex\" \"string filename\" \"a.ptx\"\n", TS_ERR_UNSUPPORTED,
         "t.pbrt:2:1: Texture \"p\": ptex textures are not supported (image textures are read from .exr, "
         ".png, .tga "
         "and .pfm files)"},
        {"Texture \"i\" \"color\" \"imagemap\" \"string filename\" \"missing.png\"\n", TS_ERR_IO,
         "t.pbrt:2:32: Texture \"i\": \"string filename\": texture image 'missing.png': cannot open (no such "
         "file or "
         "directory)"},
        {"Texture \"i\" \"color\" \"imagemap\" \"string filename\" \"pic.jpg\"\n", TS_ERR_UNSUPPORTED,
         "t.pbrt:2:32: Texture \"i\": \"string filename\": texture image 'pic.jpg': unsupported image format "
         "\".jpg\" "
         "(.exr, .png, .tga and .pfm are read)"},
        {"Texture \"i\" \"float\" \"imagemap\" \"string filename\" \"zero.pfm\"\n", TS_ERR_INVALID,
         "t.pbrt:2:32: Texture \"i\": \"string filename\": texture image 'zero.pfm': the image has a zero "
         "size (0 × 4)"},
        {"Texture \"i\" \"color\" \"imagemap\" \"string filename\" \"nan.pfm\"\n", TS_ERR_INVALID,
         "t.pbrt:2:32: Texture \"i\": \"string filename\": texture image 'nan.pfm': pixel (0, 0) is not "
         "finite or beyond ±1e30 (1, nan, 0, scale 1)"},
        {"Texture \"i\" \"color\" \"imagemap\" \"string filename\" \"../up.png\"\n", TS_ERR_INVALID,
         "t.pbrt:2:32: Texture \"i\": \"string filename\": texture image '../up.png': path leaves the "
         "scene's folder"},
        {"Texture \"i\" \"color\" \"imagemap\"\n", TS_ERR_INVALID,
         "t.pbrt:2:1: Texture \"i\": an imagemap texture needs \"string filename\""},
        {"Texture \"i\" \"color\" \"imagemap\" \"string filename\" \"x.png\" \"float maxanisotropy\" 100\n",
         TS_ERR_INVALID,
         "t.pbrt:2:58: Texture \"i\": \"float maxanisotropy\" must be in (0, 64] (tessera's bound on an EWA "
         "lookup's "
         "cost), got 100"},
        {"Texture \"i\" \"color\" \"imagemap\" \"string filename\" \"x.png\" \"string wrap\" \"mirror\"\n",
         TS_ERR_INVALID,
         "t.pbrt:2:58: Texture \"i\": \"string wrap\" must be \"repeat\", \"black\" or \"clamp\", got "
         "\"mirror\""},
        {"Texture \"u\" \"float\" \"uv\"\n", TS_ERR_INVALID,
         "t.pbrt:2:1: Texture \"u\": the uv texture is a color texture in pbrt-v3 (declare it \"color\" or "
         "\"spectrum\", not \"float\")"},
        {"Texture \"m\" \"float\" \"marble\"\n", TS_ERR_INVALID,
         "t.pbrt:2:1: Texture \"m\": the marble texture is a color texture in pbrt-v3 (declare it \"color\" "
         "or "
         "\"spectrum\", not \"float\")"},
        {"Texture \"w\" \"float\" \"wood\"\n", TS_ERR_INVALID,
         "t.pbrt:2:1: Texture \"w\": unknown texture class \"wood\""},
        {"Texture \"c\" \"float\" \"checkerboard\" \"integer dimension\" 4\n", TS_ERR_INVALID,
         "t.pbrt:2:36: Texture \"c\": \"integer dimension\" must be 2 or 3, got 4"},
        {"Texture \"c\" \"float\" \"checkerboard\" \"string aamode\" \"supersample\"\n", TS_ERR_INVALID,
         "t.pbrt:2:36: Texture \"c\": \"string aamode\" must be \"closedform\" or \"none\", got "
         "\"supersample\""},
        {"Texture \"c\" \"float\" \"checkerboard\" \"string mapping\" \"cubic\"\n", TS_ERR_INVALID,
         "t.pbrt:2:36: Texture \"c\": \"string mapping\" must be \"uv\", \"spherical\", \"cylindrical\" or "
         "\"planar\", "
         "got \"cubic\""},
        {"Texture \"f\" \"float\" \"fbm\" \"integer octaves\" 40\n", TS_ERR_INVALID,
         "t.pbrt:2:27: Texture \"f\": \"integer octaves\" must be 0 … 32 (tessera's bound on a lookup's "
         "cost), got 40"},
        {"Texture \"c\" \"color\" \"constant\"\nTexture \"s\" \"float\" \"scale\" \"texture tex1\" \"c\"\n",
         TS_ERR_INVALID,
         "t.pbrt:3:29: Texture \"s\": \"texture tex1\" names texture \"c\", a color texture, where a float "
         "texture is "
         "needed"},
        {"Scale 0 1 1\nTexture \"s\" \"color\" \"checkerboard\" \"string mapping\" \"spherical\"\n",
         TS_ERR_INVALID,
         "t.pbrt:3:1: Texture \"s\": the spherical mapping needs an invertible transformation, and this "
         "texture's is "
         "singular"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        built b;
        ts_error err = {0};
        ts_status st = build(cases[i].body, &b, &err);
        if (st != cases[i].st) fail_msg("case %zu: status %d (%s), want %d", i, st, err.message, cases[i].st);
        assert_message(&err, cases[i].msg);
        unbuild(&b);
    }
    /* Nesting deeper than TS_TEXTURE_MAX_DEPTH. */
    char body[4096] = "Texture \"t0\" \"float\" \"constant\"\n";
    for (int i = 1; i <= TS_TEXTURE_MAX_DEPTH; i++)
        snprintf(body + strlen(body), sizeof body - strlen(body),
                 "Texture \"t%d\" \"float\" \"scale\" \"texture tex1\" \"t%d\"\n", i, i - 1);
    built b;
    ts_error err = {0};
    assert_int_equal(build(body, &b, &err), TS_ERR_LIMIT);
    assert_message(&err, "t.pbrt:34:1: Texture \"t32\": scale texture: textures nest more than 32 deep");
    unbuild(&b);
    /* Issue 27: a mix of a texture with itself, within the nesting limit, is refused once one
     * lookup would evaluate more than TS_TEXTURE_MAX_COST textures (each level 1 + twice the
     * last + its constant amount: 1, 4, 10, … 1534 at t9), counted as it is built; before,
     * 31 levels were 2^31 evaluations a lookup. */
    snprintf(body, sizeof body, "Texture \"t0\" \"float\" \"constant\"\n");
    for (int i = 1; i < 31; i++)
        snprintf(body + strlen(body), sizeof body - strlen(body),
                 "Texture \"t%d\" \"float\" \"mix\" \"texture tex1\" \"t%d\" \"texture tex2\" \"t%d\"\n", i, i - 1, i - 1);
    assert_int_equal(build(body, &b, &err), TS_ERR_INVALID);
    assert_message(&err, "t.pbrt:11:1: Texture \"t9\": mix texture: one lookup of it would evaluate 1534 textures (each "
                         "use of a child counted), more than the limit of 1024");
    unbuild(&b);
}

static void test_cache_budget(void **state)
{
    (void)state;
    unsigned char px[4 * 3] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12};
    write_png("small.png", 2, 2, PNG_COLOR_TYPE_RGB, 8, PNG_INTERLACE_NONE, px, 6, NULL, 0);
    /* One 2 × 2 RGB map is (4 + 1)·3 floats = 60 bytes: a budget of 100 holds one. */
    ts_texture_cache *c = ts_texture_cache_create(100);
    cache_get(c, "small.png", 3, false, 1, TS_TEXTURE_WRAP_REPEAT);
    assert_int_equal(ts_texture_cache_bytes(c), 60);
    ts_texture_image_options opt = {
        .n_channels = 3, .gamma = true, .scale = 1, .wrap = TS_TEXTURE_WRAP_REPEAT};
    const ts_mipmap *m = NULL;
    ts_error err = {0};
    assert_int_equal(ts_texture_cache_get(c, ts_tmp_dir, "small.png", 0, &opt, &m, &err), TS_ERR_LIMIT);
    assert_message(
        &err, "texture image 'small.png': its MIP map (2 × 2, 3 channels) needs 60 bytes, more than the 40 "
              "left of the textures' 100");
    assert_null(m);
    assert_int_equal(ts_texture_cache_count(c), 1);
    /* No folder: no file may be read. */
    assert_int_equal(ts_texture_cache_get(c, NULL, "small.png", 0, &opt, &m, &err), TS_ERR_INVALID);
    assert_message(
        &err, "texture image 'small.png': this scene may not refer to files (no asset folder is configured)");
    /* The file-size limit. */
    assert_int_equal(ts_texture_cache_get(c, ts_tmp_dir, "small.png", 10, &opt, &m, &err), TS_ERR_LIMIT);
    ts_texture_cache_destroy(c);
}

static uint32_t crc32_png(const unsigned char *p, size_t n)
{
    uint32_t c = 0xFFFFFFFFu;
    for (size_t i = 0; i < n; i++) {
        c ^= p[i];
        for (int k = 0; k < 8; k++) c = c & 1 ? 0xEDB88320u ^ (c >> 1) : c >> 1;
    }
    return c ^ 0xFFFFFFFFu;
}

static void put_be32(unsigned char *p, uint32_t v)
{
    p[0] = (unsigned char)(v >> 24), p[1] = (unsigned char)(v >> 16), p[2] = (unsigned char)(v >> 8), p[3] = (unsigned char)v;
}

/* Issue 27: a small file whose header claims a huge image is refused from the header,
 * before its decoder allocates the pixels. A 1-bit grey PNG header of 16384² with 40 KB of
 * IDAT passes the decoder's own bomb check (its scanlines, 33.5 MB, are within 1032 × the
 * file), and the decoder would allocate 805 MB of bytes and 3.2 GB of floats before it
 * found the data corrupt; an RLE TGA header of 8192² with 1.1 MB of 128-pixel packets
 * likewise (800 MB). Both are refused with the MIP map's need against a 256 MiB budget —
 * before the fix the decoders ran and the answers were their corruption errors. An EXR's
 * header is read the same way (a 512² one-channel file against a 1 MiB budget). */
static void test_cache_budget_from_header(void **state)
{
    (void)state;
    size_t idat = 40000, n = 8 + 25 + 12 + idat;
    unsigned char *png = calloc(1, n);
    memcpy(png, "\x89PNG\r\n\x1a\n", 8);
    put_be32(png + 8, 13);
    memcpy(png + 12, "IHDR", 4);
    put_be32(png + 16, 16384), put_be32(png + 20, 16384);
    png[24] = 1, png[25] = 0; /* bit depth 1, grey */
    put_be32(png + 29, crc32_png(png + 12, 17));
    put_be32(png + 33, (uint32_t)idat);
    memcpy(png + 37, "IDAT", 4);
    ts_tmp_write("huge.png", png, n, NULL, 0);
    free(png);
    size_t tn = 18 + (1100u << 10);
    unsigned char *tga = malloc(tn);
    memset(tga, 0xFF, tn); /* run-length packets of 128 pixels */
    memset(tga, 0, 18);
    tga[2] = 10; /* RLE true colour */
    tga[12] = 0x00, tga[13] = 0x20, tga[14] = 0x00, tga[15] = 0x20; /* 8192 × 8192 */
    tga[16] = 24;
    ts_tmp_write("huge.tga", tga, tn, NULL, 0);
    free(tga);
    ts_image img = {0};
    const char *names[1] = {"Y"};
    assert_int_equal(ts_image_init(&img, 512, 512, 1, names, NULL), TS_OK);
    unsigned char *exr = NULL;
    size_t exr_len = 0;
    assert_int_equal(ts_exr_write_memory(&img, &exr, &exr_len, NULL), TS_OK);
    ts_image_fini(&img);
    ts_tmp_write("wide.exr", exr, exr_len, NULL, 0);
    free(exr);

    ts_texture_image_options opt = {.n_channels = 3, .gamma = true, .scale = 1, .wrap = TS_TEXTURE_WRAP_REPEAT};
    const ts_mipmap *m = NULL;
    ts_error err = {0};
    ts_texture_cache *c = ts_texture_cache_create(256u << 20);
    assert_int_equal(ts_texture_cache_get(c, ts_tmp_dir, "huge.png", 0, &opt, &m, &err), TS_ERR_LIMIT);
    assert_message(&err, "texture image 'huge.png': its MIP map (16384 × 16384, 3 channels) needs 4294967292 bytes, "
                         "more than the 268435456 left of the textures' 268435456");
    assert_int_equal(ts_texture_cache_get(c, ts_tmp_dir, "huge.tga", 0, &opt, &m, &err), TS_ERR_LIMIT);
    assert_message(&err, "texture image 'huge.tga': its MIP map (8192 × 8192, 3 channels) needs 1073741820 bytes, "
                         "more than the 268435456 left of the textures' 268435456");
    assert_int_equal(ts_texture_cache_count(c), 0);
    ts_texture_cache_destroy(c);
    c = ts_texture_cache_create(1u << 20);
    opt.n_channels = 1;
    assert_int_equal(ts_texture_cache_get(c, ts_tmp_dir, "wide.exr", 0, &opt, &m, &err), TS_ERR_LIMIT);
    assert_message(&err, "texture image 'wide.exr': its MIP map (512 × 512, 1 channel) needs 1398100 bytes, more "
                         "than the 1048576 left of the textures' 1048576");
    ts_texture_cache_destroy(c);
}

static void test_make_refusals(void **state)
{
    (void)state;
    const ts_texture *t = NULL;
    ts_error err = {0};
    ts_texture p = {.type = TS_TEXTURE_SCALE, .scale = {cf(1), crgb(1, 1, 1)}};
    assert_int_equal(ts_texture_make(&arena, &p, &t, &err), TS_ERR_INVALID);
    assert_message(&err, "scale texture: tex2 must be a float texture, not an RGB one");
    p = (ts_texture){.type = TS_TEXTURE_MIX, .is_rgb = true, .mix = {crgb(1, 1, 1), crgb(0, 0, 0), NULL}};
    assert_int_equal(ts_texture_make(&arena, &p, &t, &err), TS_ERR_INVALID);
    assert_message(&err, "mix texture: amount is missing");
    p = ts_texture_constant_float(INFINITY);
    assert_int_equal(ts_texture_make(&arena, &p, &t, &err), TS_ERR_INVALID);
    assert_message(&err, "constant texture: the value must be finite");
    float one = 1;
    ts_mipmap *m = mkmap(&one, 1, 1, 1, TS_TEXTURE_WRAP_REPEAT);
    p = (ts_texture){.type = TS_TEXTURE_IMAGEMAP,
                     .is_rgb = true,
                     .image = {.map = ts_texture_mapping2d_uv(1, 1, 0, 0), .mipmap = m, .max_anisotropy = 8}};
    assert_int_equal(ts_texture_make(&arena, &p, &t, &err), TS_ERR_INVALID);
    assert_message(&err, "imagemap texture: an RGB texture needs a 3-channel MIP map, not 1");
    p.is_rgb = false, p.image.max_anisotropy = 0;
    assert_int_equal(ts_texture_make(&arena, &p, &t, &err), TS_ERR_INVALID);
    assert_message(&err, "imagemap texture: maxanisotropy must be in (0, 64], got 0");
    ts_mipmap_destroy(m);
    assert_null(t);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_noise_permutation),
        cmocka_unit_test(test_cache_budget_from_header),
        cmocka_unit_test(test_noise_values),
        cmocka_unit_test(test_fbm_turbulence),
        cmocka_unit_test(test_mappings),
        cmocka_unit_test(test_differentials),
        cmocka_unit_test_setup_teardown(test_basic_textures, setup_arena, teardown_arena),
        cmocka_unit_test_setup_teardown(test_checkerboard_point, setup_arena, teardown_arena),
        cmocka_unit_test_setup_teardown(test_checkerboard_closed_form, setup_arena, teardown_arena),
        cmocka_unit_test_setup_teardown(test_noise_textures, setup_arena, teardown_arena),
        cmocka_unit_test_setup_teardown(test_dots, setup_arena, teardown_arena),
        cmocka_unit_test_setup_teardown(test_pbrt_dots_swapped, setup_arena, teardown_arena),
        cmocka_unit_test(test_mipmap_pyramid),
        cmocka_unit_test(test_mipmap_resample),
        cmocka_unit_test(test_mipmap_lookups),
        cmocka_unit_test(test_mipmap_ewa),
        cmocka_unit_test(test_wrap_modes),
        cmocka_unit_test(test_mipmap_refusals),
        cmocka_unit_test(test_png),
        cmocka_unit_test(test_exr),
        cmocka_unit_test(test_pfm),
        cmocka_unit_test(test_tga),
        cmocka_unit_test(test_decoder_refusals),
        cmocka_unit_test(test_pbrt_textures),
        cmocka_unit_test(test_pbrt_refusals),
        cmocka_unit_test(test_cache_budget),
        cmocka_unit_test_setup_teardown(test_make_refusals, setup_arena, teardown_arena),
    };
    return cmocka_run_group_tests(tests, ts_tmp_group_setup, ts_tmp_group_teardown);
}
