/* test_substrate.c — the anisotropic substrate (docs/design.md §4): pbrt-v3's
 * SubstrateMaterial, FresnelBlend(Kd, Ks, TrowbridgeReitz(α_u, α_v)), with α_u along dpdu
 * (the shading frame's s axis) and α_v across it, through the whole BSDF.
 *  - f against an independent double-precision evaluation of pbrt-v3's FresnelBlend
 *    formula (its own anisotropic GGX D) at fixed direction pairs, and f and pdf
 *    invariant under turning wo and wi 90° about the normal with α_u and α_v swapped;
 *  - the pdf's integral over the hemisphere against ½ + ½·(the visible-normal mass whose
 *    mirror direction stays above the surface), that mass from an independent D and Λ;
 *  - scene format v1 and the builder: uroughness / vroughness, textured roughness;
 *  - a pbrt-v3 scene with anisotropic substrates (one with a textured uroughness) renders,
 *    its `convert` document renders bit-identically, and swapping u and v changes it.
 * Its χ² tests, white furnace, reciprocity and finiteness at the limits are with the
 * other anisotropic lobes' in tests/test_material_pbrt3.c. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
/* cmocka needs the three above first */
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "chi2.h"
#include "core/hash.h"
#include "film/film.h"
#include "material_frame.h"
#include "materials/bsdf.h"
#include "materials/material.h"
#include "materials/microfacet.h"
#include "render/render.h"
#include "sampling/sampling.h"
#include "scene/scene.h"
#include "json/scene_json.h"
#include "load/scene_load.h"
#include "textures/texture_mapping.h"
#include "tmp_folder.h"

/* 90° about the normal: (x, y, z) → (−y, x, z) (exact in float). */
static ts_vec3 turn(ts_vec3 w) { return (ts_vec3){-w.y, w.x, w.z}; }

/* ------------------------------------------------- independent closed form ---- */

typedef struct dvec {
    double x, y, z;
} dvec;

static dvec dv(ts_vec3 w) { return (dvec){w.x, w.y, w.z}; }
static double ddot(dvec a, dvec b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static dvec dnorm(dvec a)
{
    double l = sqrt(ddot(a, a));
    return (dvec){a.x / l, a.y / l, a.z / l};
}
static double pow5(double x) { return x * x * x * x * x; }

/* Trowbridge–Reitz, pbrt-v3 §8.4.2: D(wh) = 1 / (π αx αy cos⁴θh (1 + tan²θh (cos²φh/αx² +
 * sin²φh/αy²))²), written from the angles. */
static double ggx_d(double ax, double ay, dvec h)
{
    double cos2 = h.z * h.z, sin2 = 1 - cos2;
    if (cos2 <= 0) return 0;
    double tan2 = sin2 / cos2, phi = atan2(h.y, h.x);
    double e = tan2 * (cos(phi) * cos(phi) / (ax * ax) + sin(phi) * sin(phi) / (ay * ay));
    return 1 / (M_PI * ax * ay * cos2 * cos2 * (1 + e) * (1 + e));
}

/* Smith Λ for Trowbridge–Reitz (pbrt-v3 §8.4.3): (−1 + √(1 + α²tan²θ)) / 2, α² =
 * αx²cos²φ + αy²sin²φ. */
static double ggx_lambda(double ax, double ay, dvec w)
{
    double sin2 = w.x * w.x + w.y * w.y;
    if (sin2 == 0) return 0;
    double phi = atan2(w.y, w.x), a2 = ax * ax * cos(phi) * cos(phi) + ay * ay * sin(phi) * sin(phi);
    return (-1 + sqrt(1 + a2 * sin2 / (w.z * w.z))) / 2;
}

/* pbrt-v3's FresnelBlend::f (reflection.cpp), channel by channel:
 *   28/(23π) Rd (1 − Rs) (1 − (1 − |cosθi|/2)⁵)(1 − (1 − |cosθo|/2)⁵)
 *   + D(wh) / (4 |wi·wh| max(|cosθi|, |cosθo|)) · (Rs + (1 − wi·wh)⁵ (1 − Rs)). */
static double blend_f(double rd, double rs, double ax, double ay, ts_vec3 wo_f, ts_vec3 wi_f)
{
    dvec wo = dv(wo_f), wi = dv(wi_f);
    if (wo.z * wi.z <= 0) return 0;
    double ci = fabs(wi.z), co = fabs(wo.z);
    double diffuse = 28 / (23 * M_PI) * rd * (1 - rs) * (1 - pow5(1 - ci / 2)) * (1 - pow5(1 - co / 2));
    dvec wh = dnorm((dvec){wi.x + wo.x, wi.y + wo.y, wi.z + wo.z});
    double c = ddot(wi, wh);
    return diffuse + ggx_d(ax, ay, wh) / (4 * fabs(c) * fmax(ci, co)) * (rs + pow5(1 - c) * (1 - rs));
}

/* f at fixed pairs against blend_f: relative 2e-5 (float against double: D and the
 * half vector carry a few float roundings each, each ≤ 6e-8 relative, amplified at most
 * ~10× by the (1 + e)² at these angles). α = (0.08, 0.45), coloured Rd and Rs. Each pair
 * also differs by more than 20% from the same formula with α swapped, so the check sees
 * which axis α_u belongs to (dpdu = +x). */
static void test_closed_form(void **state)
{
    (void)state;
    const ts_rgb rd = {0.2f, 0.5f, 0.8f}, rs = {0.04f, 0.1f, 0.3f};
    const float ax = 0.08f, ay = 0.45f;
    ts_material m = substrate_rgb(rd, rs, ax, ay);
    ts_bsdf b;
    canonical_bsdf(&m, &b);
    assert_int_equal(b.n_bxdfs, 1);
    /* (θo, φo, θi, φi) in degrees: a near-mirror pair whose half vector leans along x, one
     * along y, one at 30°, a grazing one, and one below the surface (both sides flip). */
    const double pairs[][4] = {
        {40, 0, 44, 180}, {40, 90, 44, 270}, {30, 30, 50, 200}, {75, 10, 70, 160}, {140, 60, 130, 250},
    };
    for (size_t k = 0; k < sizeof pairs / sizeof pairs[0]; k++) {
        ts_vec3 wo = dir_cos(cos(pairs[k][0] * M_PI / 180), pairs[k][1] * M_PI / 180);
        ts_vec3 wi = dir_cos(cos(pairs[k][2] * M_PI / 180), pairs[k][3] * M_PI / 180);
        ts_rgb f = ts_bsdf_f(&b, wo, wi);
        const float got[3] = {f.r, f.g, f.b}, d[3] = {rd.r, rd.g, rd.b}, s[3] = {rs.r, rs.g, rs.b};
        for (int c = 0; c < 3; c++) {
            double want = blend_f(d[c], s[c], ax, ay, wo, wi), swapped = blend_f(d[c], s[c], ay, ax, wo, wi);
            print_message("pair %zu channel %d: f %.7g, closed form %.7g (α swapped: %.5g)\n", k, c, got[c],
                          want, swapped);
            assert_true(fabs(swapped - want) > 0.2 * want);
            if (!(fabs(got[c] - want) <= 2e-5 * want))
                fail_msg("pair %zu channel %d: f %.9g, closed form %.9g", k, c, got[c], want);
        }
    }
}

/* f and pdf at (turn wo, turn wi) with α_u and α_v swapped equal f and pdf at (wo, wi):
 * relative 1e-5 (the same terms, x and y exchanged), over 10⁴ random pairs on both
 * sides, for three α pairs. */
static void test_turn_swap(void **state)
{
    (void)state;
    const float as[][2] = {{0.05f, 0.5f}, {0.3f, 0.1f}, {0.01f, 1.0f}};
    ts_pcg32 rng;
    ts_pcg32_seed(&rng, 6, 6);
    for (size_t k = 0; k < sizeof as / sizeof as[0]; k++) {
        ts_material m1 = substrate_aniso(0.6f, 0.2f, as[k][0], as[k][1]);
        ts_material m2 = substrate_aniso(0.6f, 0.2f, as[k][1], as[k][0]);
        ts_bsdf b1, b2;
        canonical_bsdf(&m1, &b1);
        canonical_bsdf(&m2, &b2);
        for (int i = 0; i < 10000; i++) {
            ts_vec3 wo = ts_sample_uniform_sphere((ts_vec2){ts_pcg32_float(&rng), ts_pcg32_float(&rng)});
            ts_vec3 wi = ts_sample_uniform_sphere((ts_vec2){ts_pcg32_float(&rng), ts_pcg32_float(&rng)});
            float f1 = ts_bsdf_f(&b1, wo, wi).g, f2 = ts_bsdf_f(&b2, turn(wo), turn(wi)).g;
            float p1 = ts_bsdf_pdf(&b1, wo, wi), p2 = ts_bsdf_pdf(&b2, turn(wo), turn(wi));
            if (!(fabsf(f1 - f2) <= 1e-5f * f1 + 1e-12f && fabsf(p1 - p2) <= 1e-5f * p1 + 1e-12f))
                fail_msg("α (%g, %g): f %.9g / %.9g, pdf %.9g / %.9g", as[k][0], as[k][1], f1, f2, p1, p2);
        }
    }
}

/* ------------------------------------------------------- ∫pdf over H² ---- */

typedef struct pdf_ctx {
    const ts_bsdf *b;
    ts_vec3 wo;
    double ax, ay;
} pdf_ctx;

static double bsdf_pdf_at(void *ctx, ts_vec3 wi)
{
    const pdf_ctx *c = ctx;
    return ts_bsdf_pdf(c->b, c->wo, wi);
}

/* The distribution of visible normals from the closed forms above, D_wo(wh) = G1(wo)
 * max(0, wo·wh) D(wh) / cosθo (Heitz 2014; pbrt-v3's Pdf with sampleVisibleArea), 0 where
 * wh.z ≤ 0; with keep, also 0 where wo mirrored about wh falls below the surface (pbrt-v3's
 * FresnelBlend::Sample_f returns no sample there). */
static double visible(const pdf_ctx *c, ts_vec3 wh_f, bool keep)
{
    dvec wo = dv(c->wo), wh = dv(wh_f);
    double dot = ddot(wo, wh);
    if (wh.z <= 0 || dot <= 0) return 0;
    if (keep && 2 * dot * wh.z - wo.z <= 0) return 0;
    return ggx_d(c->ax, c->ay, wh) * dot / wo.z / (1 + ggx_lambda(c->ax, c->ay, wo));
}
static double visible_all(void *ctx, ts_vec3 wh) { return visible(ctx, wh, false); }
static double visible_kept(void *ctx, ts_vec3 wh) { return visible(ctx, wh, true); }

/* FresnelBlend's pdf is ½ cosθi/π + ½ D_wo(wh)/(4 wo·wh) on wo's hemisphere. Its cosine
 * half integrates to ½; its glossy half is the visible-normal density carried to wi by
 * the mirror Jacobian dωh/dωi = 1/(4 wo·wh), so over the hemisphere it integrates to ½ of
 * the visible-normal mass K whose mirror direction stays above the surface, and
 * ∫_H² pdf dωi = ½ + ½K ≤ 1 — equal to 1 once the lost mirror directions are counted,
 * which is what the χ² harness's ∫pdf = fraction-of-directions check states on samples.
 * Here the two sides come from different code and different variables: ∫pdf dωi from
 * the renderer's pdf over wi, K and the total visible mass (= 1, the normalisation of
 * D_wo) from the closed forms over wh. Both by ts_chi2_integrate (11 × 22 cells, absolute
 * tolerance 1e-5 per integral); K's integrand is cut along a curve, where the adaptive
 * rule converges slowest, so the comparison allows 2e-4 (the measured differences, ≤ 1e-6
 * and 5e-6 for ∫D_wo at normal incidence, are printed; the bound is deterministic). */
static void test_pdf_integral(void **state)
{
    (void)state;
    const struct {
        float ax, ay, theta;
    } cases[] = {{0.1f, 0.4f, 0}, {0.6f, 0.1f, 30}, {0.3f, 0.9f, 75}};
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        ts_material m = substrate_aniso(0.5f, 0.5f, cases[k].ax, cases[k].ay);
        ts_bsdf b;
        canonical_bsdf(&m, &b);
        pdf_ctx c = {&b, dir_cos(cos(cases[k].theta * M_PI / 180), 0.6), cases[k].ax, cases[k].ay};
        double all = ts_chi2_integrate(visible_all, &c, 11, 22, 1e-5);
        double kept = ts_chi2_integrate(visible_kept, &c, 11, 22, 1e-5);
        double integral = ts_chi2_integrate(bsdf_pdf_at, &c, 11, 22, 1e-5);
        print_message("α=(%g,%g) θo=%g°: ∫D_wo=%.6f kept K=%.6f ∫pdf=%.6f ½+½K=%.6f\n", cases[k].ax,
                      cases[k].ay, cases[k].theta, all, kept, integral, 0.5 + 0.5 * kept);
        assert_true(fabs(all - 1) <= 2e-4);
        assert_true(fabs(integral - (0.5 + 0.5 * kept)) <= 2e-4);
        assert_true(integral <= 1 + 2e-4);
    }
}

/* --------------------------------------------------- JSON and textures ---- */

static ts_scene *load_json(const char *doc)
{
    ts_scene *s = NULL;
    ts_error err = {0};
    if (ts_scene_load_text(doc, strlen(doc), NULL, "t", NULL, &s, &err)) fail_msg("%s", err.message);
    return s;
}

static void expect_json_error(const char *doc, const char *sentence)
{
    ts_scene *s = NULL;
    ts_error err = {0};
    assert_int_not_equal(ts_scene_load_text(doc, strlen(doc), NULL, "t", NULL, &s, &err), TS_OK);
    assert_null(s);
    if (strcmp(err.message, sentence) != 0)
        fprintf(stderr, "got:      %s\nexpected: %s\n", err.message, sentence);
    assert_string_equal(err.message, sentence);
}

/* Scene format v1: substrate takes uroughness / vroughness, each defaulting to roughness
 * (anisotropic only when they differ), as dielectric, conductor and uber do; a float
 * texture may stand for either, and the BSDF read at a hit takes the texture's value. */
static void test_json(void **state)
{
    (void)state;
    const char *doc = "{\"tessera\":1,\"camera\":{\"from\":[0,0,5],\"to\":[0,0,0]},"
                      "\"textures\":{\"r\":{\"type\":\"constant\",\"kind\":\"float\",\"value\":0.05}},"
                      "\"materials\":{"
                      "\"a\":{\"type\":\"substrate\",\"uroughness\":0.05,\"vroughness\":0.4},"
                      "\"b\":{\"type\":\"substrate\",\"vroughness\":0.3,\"remap_roughness\":true},"
                      "\"c\":{\"type\":\"substrate\",\"roughness\":0.2,\"uroughness\":0.2},"
                      "\"d\":{\"type\":\"substrate\",\"uroughness\":\"r\",\"vroughness\":0.4}}}";
    ts_scene *s = load_json(doc);
    const ts_material *a = &s->materials[0], *b = &s->materials[1], *c = &s->materials[2],
                      *d = &s->materials[3];
    assert_true(a->type == TS_MATERIAL_SUBSTRATE && a->roughness.value == 0.05f && a->has_vroughness &&
                a->vroughness.value == 0.4f && !a->remap_roughness && a->diffuse.value.g == 0.5f &&
                a->specular.value.g == 0.5f);
    assert_true(b->roughness.value == 0.1f && b->has_vroughness && b->vroughness.value == 0.3f &&
                b->remap_roughness);
    assert_true(c->roughness.value == 0.2f && !c->has_vroughness);
    assert_true(d->roughness.tex && d->textured && d->has_vroughness && d->vroughness.value == 0.4f);
    /* The textured one's BSDF at a hit is the constant one's, bit for bit. */
    ts_interaction si;
    memset(&si, 0, sizeof si);
    si.n = si.ns = (ts_vec3){0, 0, 1};
    si.dpdu = (ts_vec3){1, 0, 0};
    si.dpdv = (ts_vec3){0, 1, 0};
    si.uv = (ts_vec2){0.3f, 0.6f};
    ts_texture_context tc;
    ts_material_texture_context(&si, &tc);
    ts_bsdf bt, bc;
    ts_material_bsdf(d, &si, &tc, &bt);
    ts_material_bsdf(a, &si, NULL, &bc);
    assert_true(bt.n_bxdfs == 1 && bt.bxdfs[0].dist.alpha_x == 0.05f && bt.bxdfs[0].dist.alpha_y == 0.4f);
    ts_pcg32 rng;
    ts_pcg32_seed(&rng, 2, 2);
    for (int i = 0; i < 1000; i++) {
        ts_vec3 wo = ts_sample_uniform_sphere((ts_vec2){ts_pcg32_float(&rng), ts_pcg32_float(&rng)});
        ts_vec3 wi = ts_sample_uniform_sphere((ts_vec2){ts_pcg32_float(&rng), ts_pcg32_float(&rng)});
        ts_rgb f1 = ts_bsdf_f(&bt, wo, wi), f2 = ts_bsdf_f(&bc, wo, wi);
        assert_true(memcmp(&f1, &f2, sizeof f1) == 0 && ts_bsdf_pdf(&bt, wo, wi) == ts_bsdf_pdf(&bc, wo, wi));
    }
    ts_scene_destroy(s);
    expect_json_error("{\"tessera\":1,\"camera\":{\"from\":[0,0,5],\"to\":[0,0,0]},\"materials\":{"
                      "\"s\":{\"type\":\"substrate\",\"vroughness\":-1}}}",
                      "materials.s.vroughness: expected a non-negative number, got -1");
}

/* ---------------------------------------------------- pbrt-v3 scene ---- */

/* A floor of anisotropic substrate under a point light (remapped roughness, pbrt-v3's
 * default: r = (0.02, 0.3) is α ≈ (0.19, 0.86)) and a sphere whose uroughness is a
 * checkerboard texture; %s and %s are the floor's u and v roughness, %s its uv. */
static const char scene_fmt[] =
    "LookAt 0 2.5 3  0 0 0  0 1 0\n"
    "Camera \"perspective\" \"float fov\" 45\n"
    "Film \"image\" \"integer xresolution\" 32 \"integer yresolution\" 24\n"
    "Sampler \"sobol\" \"integer pixelsamples\" 4\n"
    "Integrator \"path\" \"integer maxdepth\" 3\n"
    "WorldBegin\n"
    "LightSource \"point\" \"point from\" [0.3 2 -0.5] \"rgb I\" [8 8 8]\n"
    "Texture \"r\" \"float\" \"checkerboard\" \"float tex1\" 0.01 \"float tex2\" 0.3 \"float uscale\" 8\n"
    "AttributeBegin\n"
    "  Material \"substrate\" \"rgb Kd\" [0.2 0.3 0.4] \"rgb Ks\" [0.4 0.4 0.4] \"float uroughness\" %s "
    "\"float vroughness\" %s\n"
    "  Shape \"trianglemesh\" \"point P\" [-2 0 -2  2 0 -2  2 0 2  -2 0 2] \"integer indices\" [0 1 2 0 2 "
    "3]\n"
    "    \"float uv\" [%s]\n"
    "AttributeEnd\n"
    "AttributeBegin Translate 0.6 0.4 0.3\n"
    "  Material \"substrate\" \"texture uroughness\" \"r\" \"float vroughness\" 0.4\n"
    "  Shape \"sphere\" \"float radius\" 0.4\n"
    "AttributeEnd\n"
    "WorldEnd\n";

static ts_film *render(const ts_scene *s)
{
    ts_error err = {0};
    ts_film *f = ts_film_create(s->width, s->height, s->crop_x0, s->crop_y0, s->crop_x1 - s->crop_x0,
                                s->crop_y1 - s->crop_y0, &err);
    assert_non_null(f);
    ts_render_stats st = {0};
    ts_render_request req = {s, s->integrator.type, f, 0, 4, 1, NULL, NULL, NULL};
    assert_int_equal(ts_render(&req, &st, &err), TS_OK);
    return f;
}

/* Σ|a − b| over the pixels and channels, and Σ a (all finite: no NaN reaches the film). */
static void compare(const ts_scene *s, const ts_film *a, const ts_film *b, double *diff, double *sum,
                    int *differ)
{
    *diff = *sum = 0;
    *differ = 0;
    for (int y = s->crop_y0; y < s->crop_y1; y++)
        for (int x = s->crop_x0; x < s->crop_x1; x++) {
            ts_rgb p = ts_film_pixel_rgb(a, x, y), q = ts_film_pixel_rgb(b, x, y);
            assert_true(ts_rgb_is_finite(p) && ts_rgb_is_finite(q));
            *differ += memcmp(&p, &q, sizeof p) != 0;
            *diff += fabs(p.r - q.r) + fabs(p.g - q.g) + fabs(p.b - q.b);
            *sum += p.r + p.g + p.b;
        }
}

static ts_scene *load_pbrt(const char *path)
{
    ts_scene *s = NULL;
    ts_error err = {0};
    if (ts_scene_load_path(path, NULL, NULL, NULL, &s, &err)) fail_msg("%s", err.message);
    return s;
}

/* The scene loads with pbrt-v3's meaning (uroughness along dpdu, vroughness across,
 * remapped), renders a finite, non-black image; `convert`'s document carries uroughness
 * and vroughness (and the textured one) and renders bit-identically; the same floor with
 * u and v swapped renders differently (by more than 5% of the image's sum: the highlight
 * stretches the other way), so the two parameters reach the image; and swapped on a
 * floor whose uv is turned 90° (u' = v, v' = 1 − u: dpdu' is the old dpdv) renders the
 * first image again, so uroughness lies along dpdu end to end: mesh uv, shading frame,
 * BSDF. Not bit for bit: the same random numbers drive both renders, but the turned
 * frame's float roundings differ and now and then send a sample down another path
 * (measured: 28 of 768 pixels differ, Σ|Δ| 0.3% of the sum). The renders are
 * deterministic, so the bounds — at most 10% of the pixels and Σ|Δ| ≤ 1% of the sum,
 * against 76% for the swap without the turn — only leave room for other float rounding. */
static void test_pbrt_scene(void **state)
{
    (void)state;
    char text[4096], path[512], swapped_path[512], turned_path[512];
    const char *uv = "0 0 1 0 1 1 0 1", *uv_turned = "0 1 0 0 1 0 1 1";
    snprintf(text, sizeof text, scene_fmt, "0.02", "0.3", uv);
    ts_tmp_write("aniso.pbrt", text, strlen(text), path, sizeof path);
    snprintf(text, sizeof text, scene_fmt, "0.3", "0.02", uv);
    ts_tmp_write("swapped.pbrt", text, strlen(text), swapped_path, sizeof swapped_path);
    snprintf(text, sizeof text, scene_fmt, "0.3", "0.02", uv_turned);
    ts_tmp_write("turned.pbrt", text, strlen(text), turned_path, sizeof turned_path);

    ts_scene *a = load_pbrt(path);
    const ts_material *floor = &a->materials[a->shapes[0].material],
                      *ball = &a->materials[a->shapes[1].material];
    assert_true(floor->type == TS_MATERIAL_SUBSTRATE && floor->roughness.value == 0.02f &&
                floor->has_vroughness && floor->vroughness.value == 0.3f && floor->remap_roughness);
    assert_true(ball->roughness.tex && ball->has_vroughness && ball->vroughness.value == 0.4f &&
                ball->textured);

    char *json = NULL;
    size_t len = 0;
    ts_error err = {0};
    assert_int_equal(ts_scene_convert_pbrt_path(path, NULL, NULL, NULL, &json, &len, &err), TS_OK);
    assert_non_null(strstr(json, "\"vroughness\""));
    ts_scene *b = NULL;
    if (ts_scene_load_text(json, len, ts_tmp_dir, "aniso", NULL, &b, &err)) fail_msg("%s", err.message);
    free(json);
    ts_scene *c = load_pbrt(swapped_path), *d = load_pbrt(turned_path);

    ts_film *fa = render(a), *fb = render(b), *fc = render(c), *fd = render(d);
    double diff, sum;
    int differ;
    compare(a, fa, fb, &diff, &sum, &differ);
    print_message("pbrt-v3 scene against its conversion: %d pixels differ, image sum %.4f\n", differ, sum);
    assert_int_equal(differ, 0);
    assert_true(sum > 0);
    compare(a, fa, fc, &diff, &sum, &differ);
    print_message("u and v swapped: Σ|Δ| = %.4f of %.4f (%.1f%%)\n", diff, sum, 100 * diff / sum);
    assert_true(diff > 0.05 * sum);
    compare(a, fa, fd, &diff, &sum, &differ);
    print_message("u and v swapped on the turned floor: Σ|Δ| = %.3g of %.4f (%.2g), %d pixels differ\n", diff,
                  sum, diff / sum, differ);
    assert_true(diff <= 0.01 * sum && differ <= (a->crop_x1 - a->crop_x0) * (a->crop_y1 - a->crop_y0) / 10);
    ts_film_destroy(fa);
    ts_film_destroy(fb);
    ts_film_destroy(fc);
    ts_film_destroy(fd);
    ts_scene_destroy(a);
    ts_scene_destroy(b);
    ts_scene_destroy(c);
    ts_scene_destroy(d);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_closed_form),  cmocka_unit_test(test_turn_swap),
        cmocka_unit_test(test_pdf_integral), cmocka_unit_test(test_json),
        cmocka_unit_test(test_pbrt_scene),
    };
    return cmocka_run_group_tests(tests, ts_tmp_group_setup, ts_tmp_group_teardown);
}
