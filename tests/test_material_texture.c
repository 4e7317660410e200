/* test_material_texture.c — texture-valued material parameters (docs/design.md §4d):
 * scene format v1's "textures" section and texture references, through the builder to the
 * BSDF at a hit; the clamping of textured values; the builder's texture calls and its
 * refusals; what the effects analysis makes of a textured material.
 *
 * Every check here is exact (values the code computes without noise), so there is no
 * false-failure rate to name: a BSDF's f for a Lambertian lobe is R/π computed in float by
 * the same expression, compared to 1e-6 relative. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
// clang-format off
#include <cmocka.h>
// clang-format on

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "integrators/effects.h"
#include "materials/bsdf.h"
#include "materials/material.h"
#include "render/render.h"
#include "scene/scene.h"
#include "build/scene_builder.h"
#include "json/scene_json.h"
#include "textures/texture.h"

#define HEAD                                                                                                 \
    "{\"tessera\":1,\"camera\":{\"from\":[0,0,5],\"to\":[0,0,0]},\"film\":{\"width\":8,\"height\":8},"       \
    "\"lights\":[{\"type\":\"point\",\"position\":[0,0,3],\"intensity\":1}],"
#define PLANE                                                                                                \
    "\"shapes\":[{\"type\":\"mesh\",\"positions\":[-1,-1,0,1,-1,0,1,1,0,-1,1,0],\"indices\":[0,1,2,0,2,3],"  \
    "\"uvs\":[0,0,1,0,1,1,0,1],\"material\":\"m\"}]}"

static ts_scene *load(const char *doc, const char *base_dir)
{
    ts_scene *s = NULL;
    ts_error err = {0};
    if (ts_scene_load_text(doc, strlen(doc), base_dir, "t", NULL, &s, &err)) fail_msg("%s", err.message);
    return s;
}

static void refused(const char *doc, const char *want)
{
    ts_scene *s = NULL;
    ts_error err = {0};
    ts_status st = ts_scene_load_text(doc, strlen(doc), NULL, "t", NULL, &s, &err);
    if (st == TS_OK) fail_msg("accepted, expected \"%s\"", want);
    if (!strstr(err.message, want)) fail_msg("got \"%s\", expected \"%s\"", err.message, want);
    assert_null(s);
}

static const ts_material *material(const ts_scene *s, const char *name)
{
    for (uint32_t i = 0; i < s->n_materials; i++)
        if (s->material_names[i] && strcmp(s->material_names[i], name) == 0) return &s->materials[i];
    fail_msg("no material %s", name);
    return NULL;
}

/* A hit on the z = 0 plane at (u, v), facing +z, with its texture context. */
static ts_interaction hit(float u, float v, ts_texture_context *c)
{
    ts_interaction si = {0};
    si.p = (ts_vec3){2 * u - 1, 2 * v - 1, 0};
    si.n = si.ns = (ts_vec3){0, 0, 1};
    si.dpdu = (ts_vec3){2, 0, 0};
    si.dpdv = (ts_vec3){0, 2, 0};
    si.uv = (ts_vec2){u, v};
    si.wo = (ts_vec3){0, 0, 1};
    ts_material_texture_context(&si, c);
    return si;
}

/* The Lambertian reflectance of the BSDF at (u, v): f(n, n)·π. */
static ts_rgb lambert_at(const ts_material *m, float u, float v)
{
    ts_texture_context c;
    ts_interaction si = hit(u, v, &c);
    ts_bsdf b;
    ts_material_bsdf(m, &si, &c, &b);
    assert_int_equal(b.n_bxdfs, 1);
    ts_vec3 n = {0, 0, 1};
    return ts_rgb_scale(ts_bsdf_f(&b, n, n), (float)M_PI);
}

static void near_rgb(ts_rgb got, ts_rgb want)
{
    const float tol = 1e-6f;
    if (fabsf(got.r - want.r) > tol * fmaxf(1, want.r) || fabsf(got.g - want.g) > tol * fmaxf(1, want.g) ||
        fabsf(got.b - want.b) > tol * fmaxf(1, want.b))
        fail_msg("got (%.9g, %.9g, %.9g), want (%.9g, %.9g, %.9g)", got.r, got.g, got.b, want.r, want.g,
                 want.b);
}

/* A checkerboard reflectance from JSON reaches the BSDF: tex1 on even checks, tex2 on odd. */
static void test_json_checkerboard_reflectance(void **state)
{
    (void)state;
    ts_scene *s = load(
        HEAD "\"textures\":{\"checks\":{\"type\":\"checkerboard\",\"aamode\":\"none\","
             "\"mapping\":{\"type\":\"uv\",\"uscale\":2,\"vscale\":2},\"tex1\":[0.8,0.2,0.1],"
             "\"tex2\":0.3}},\"materials\":{\"m\":{\"type\":\"diffuse\",\"reflectance\":\"checks\"}}," PLANE,
        NULL);
    const ts_material *m = material(s, "m");
    assert_true(m->textured);
    assert_non_null(m->reflectance.tex);
    near_rgb(lambert_at(m, 0.1f, 0.1f), (ts_rgb){0.8f, 0.2f, 0.1f}); /* (0.2, 0.2): even */
    near_rgb(lambert_at(m, 0.6f, 0.1f), ts_rgb_gray(0.3f));          /* (1.2, 0.2): odd */
    near_rgb(lambert_at(m, 0.6f, 0.7f), (ts_rgb){0.8f, 0.2f, 0.1f}); /* (1.2, 1.4): even */
    ts_scene_destroy(s);
}

/* Through the renderer: an orthographic view of a checkerboard plane lit head-on by a
 * distant light of irradiance π, so each pixel is the reflectance of its check (L = R/π·E,
 * no noise: one unoccluded delta light, R constant over every pixel, as each check covers
 * 2 × 2 pixels, and aamode none point-samples it), to float rounding (1e-5). */
static void test_render_checkerboard(void **state)
{
    (void)state;
    const char *doc =
        "{\"tessera\":1,\"camera\":{\"type\":\"orthographic\",\"from\":[0,0,5],\"to\":[0,0,0],\"height\":2},"
        "\"film\":{\"width\":8,\"height\":8,\"filter\":{\"type\":\"box\"}},\"sampler\":{\"spp\":4},"
        "\"integrator\":{\"type\":\"direct\"},"
        "\"lights\":[{\"type\":\"distant\",\"from\":[0,0,1],\"to\":[0,0,0],\"irradiance\":3.14159265358979}],"
        "\"textures\":{\"checks\":{\"type\":\"checkerboard\",\"aamode\":\"none\",\"mapping\":{\"uscale\":4,\"vscale\":4},"
        "\"tex1\":[0.8,0.5,0.2],\"tex2\":0.1}},"
        "\"materials\":{\"m\":{\"type\":\"diffuse\",\"reflectance\":\"checks\"}}," PLANE;
    ts_scene *s = load(doc, NULL);
    ts_error err = {0};
    ts_film *f = ts_film_create(s->width, s->height, 0, 0, s->width, s->height, &err);
    assert_non_null(f);
    ts_render_stats stats = {0};
    ts_render_request req = {s, s->integrator.type, f, 0, 4, 2, NULL, NULL, NULL};
    assert_int_equal(ts_render(&req, &stats, &err), TS_OK);
    for (int y = 0; y < 8; y++)
        for (int x = 0; x < 8; x++) {
            bool odd = ((x / 2) + (7 - y) / 2) % 2 == 1; /* u = (x + ½)/8, v = 1 − (y + ½)/8 */
            ts_rgb want = odd ? ts_rgb_gray(0.1f) : (ts_rgb){0.8f, 0.5f, 0.2f},
                   got = ts_film_pixel_rgb(f, x, y);
            if (fabsf(got.r - want.r) > 1e-5f || fabsf(got.g - want.g) > 1e-5f ||
                fabsf(got.b - want.b) > 1e-5f)
                fail_msg("pixel (%d, %d): (%g, %g, %g), want (%g, %g, %g)", x, y, got.r, got.g, got.b, want.r,
                         want.g, want.b);
        }
    ts_film_destroy(f);
    ts_scene_destroy(s);
}

/* Bump mapping (pbrt-v3's Material::Bump) with a displacement linear in u, d = a·s with
 * s = u (a float bilerp 0 → a): on a plane with ∂p/∂u = (2, 0, 0), ∂p/∂v = (0, 2, 0) and
 * normal +z, the displaced tangent is ∂p'/∂u = (2, 0, a) (the difference quotient of a
 * linear d is a for any du), ∂p'/∂v = (0, 2, 0), so the shading normal is
 * (∂p'/∂u × ∂p'/∂v)/|…| = (−a, 0, 2)/√(4 + a²): tilted by atan(a/|∂p/∂u|) against u.
 * Likewise in v. Exact but for rounding, which the difference quotient amplifies: d is
 * rounded to ≈ 6e-8·a, divided by du = 0.0005 (no footprint) that is ≈ 1e-4·a in the slope
 * (measured 3e-6 in the normal); the bound is 1e-4. Rendered head-on under a distant light
 * of irradiance π (as test_render_checkerboard), a diffuse R reflects R·cosθ' =
 * R·2/√(4 + a²) (1e-4, the same rounding). */
static void test_bump_linear(void **state)
{
    (void)state;
    const float a = 0.5f;
    ts_scene *s = load(HEAD "\"textures\":{\"du\":{\"type\":\"bilerp\",\"kind\":\"float\",\"v00\":0,\"v01\":0,"
                            "\"v10\":0.5,\"v11\":0.5},\"dv\":{\"type\":\"bilerp\",\"kind\":\"float\",\"v00\":0,"
                            "\"v01\":0.5,\"v10\":0,\"v11\":0.5}},"
                            "\"materials\":{\"m\":{\"type\":\"diffuse\",\"bumpmap\":\"du\"},"
                            "\"n\":{\"type\":\"mirror\",\"bumpmap\":\"dv\"}}," PLANE,
                       NULL);
    const ts_material *m = material(s, "m"), *n = material(s, "n");
    assert_true(m->textured && n->textured);
    float k = 1 / sqrtf(4 + a * a);
    for (int with_footprint = 0; with_footprint < 2; with_footprint++) {
        ts_texture_context c;
        ts_interaction si = hit(0.3f, 0.6f, &c);
        if (with_footprint) c.dudx = 0.01f, c.dvdy = 0.02f, c.dudy = -0.003f;
        ts_interaction sj = si;
        ts_material_bump(m, &si, &c);
        ts_material_bump(n, &sj, &c);
        ts_vec3 wu = {-a * k, 0, 2 * k}, wv = {0, -a * k, 2 * k};
        if (ts_vec3_length(ts_vec3_sub(si.ns, wu)) > 1e-4f || ts_vec3_length(ts_vec3_sub(sj.ns, wv)) > 1e-4f)
            fail_msg("bumped normals (%g, %g, %g) and (%g, %g, %g)", si.ns.x, si.ns.y, si.ns.z, sj.ns.x, sj.ns.y,
                     sj.ns.z);
        assert_true(si.n.z == 1); /* the geometric normal stays */
    }
    ts_scene_destroy(s);

    char doc[1500];
    snprintf(doc, sizeof doc,
             "{\"tessera\":1,\"camera\":{\"type\":\"orthographic\",\"from\":[0,0,5],\"to\":[0,0,0],\"height\":2},"
             "\"film\":{\"width\":4,\"height\":4,\"filter\":{\"type\":\"box\"}},\"sampler\":{\"spp\":2},"
             "\"integrator\":{\"type\":\"direct\"},"
             "\"lights\":[{\"type\":\"distant\",\"from\":[0,0,1],\"to\":[0,0,0],\"irradiance\":3.14159265358979}],"
             "\"textures\":{\"du\":{\"type\":\"bilerp\",\"kind\":\"float\",\"v00\":0,\"v01\":0,\"v10\":%g,"
             "\"v11\":%g}},\"materials\":{\"m\":{\"type\":\"diffuse\",\"reflectance\":0.5,\"bumpmap\":\"du\"}},"
             PLANE,
             a, a);
    s = load(doc, NULL);
    ts_error err = {0};
    ts_film *f = ts_film_create(s->width, s->height, 0, 0, s->width, s->height, &err);
    ts_render_stats stats = {0};
    ts_render_request req = {s, s->integrator.type, f, 0, 2, 1, NULL, NULL, NULL};
    assert_int_equal(ts_render(&req, &stats, &err), TS_OK);
    for (int y = 0; y < 4; y++)
        for (int x = 0; x < 4; x++) {
            float got = ts_film_pixel_rgb(f, x, y).g;
            if (fabsf(got - 0.5f * 2 * k) > 1e-4f) fail_msg("pixel (%d, %d): %.7g, want %.7g", x, y, got, k);
        }
    ts_film_destroy(f);
    ts_scene_destroy(s);
}

/* A constant material is not textured, and its BSDF does not depend on the context. */
static void test_constant_material_ignores_context(void **state)
{
    (void)state;
    ts_scene *s = load(HEAD "\"materials\":{\"m\":{\"type\":\"plastic\",\"diffuse\":[0.5,0.4,0.3],"
                            "\"roughness\":0.2}}," PLANE,
                       NULL);
    const ts_material *m = material(s, "m");
    assert_false(m->textured);
    ts_texture_context c;
    ts_interaction si = hit(0.3f, 0.4f, &c);
    ts_bsdf with, without;
    ts_material_bsdf(m, &si, &c, &with);
    ts_material_bsdf(m, &si, NULL, &without);
    ts_vec3 wo = {0.3f, 0.1f, 0.9f}, wi = {-0.2f, 0.4f, 0.8f};
    ts_rgb a = ts_bsdf_f(&with, wo, wi), b = ts_bsdf_f(&without, wo, wi);
    assert_memory_equal(&a, &b, sizeof a);
    assert_true(a.r > 0);
    ts_scene_destroy(s);
}

/* Textured values are clamped into the constants' ranges: a reflectance of 2 is 1, a
 * roughness of −0.3 is 0 (a specular lobe), σ of 120 is 90, η of 0 is TS_MATERIAL_ETA_MIN. */
static void test_textured_values_clamped(void **state)
{
    (void)state;
    ts_scene *s = load(HEAD "\"textures\":{\"two\":{\"type\":\"scale\",\"tex1\":4,\"tex2\":[0.5,0.25,0.5]},"
                            "\"neg\":{\"type\":\"constant\",\"kind\":\"float\",\"value\":-0.3},"
                            "\"wide\":{\"type\":\"constant\",\"kind\":\"float\",\"value\":120},"
                            "\"zero\":{\"type\":\"constant\",\"kind\":\"float\",\"value\":0}},"
                            "\"materials\":{\"m\":{\"type\":\"diffuse\",\"reflectance\":\"two\"},"
                            "\"on\":{\"type\":\"diffuse\",\"reflectance\":0.5,\"sigma\":\"wide\"},"
                            "\"on90\":{\"type\":\"diffuse\",\"reflectance\":0.5,\"sigma\":90},"
                            "\"metal\":{\"type\":\"conductor\",\"eta\":0.2,\"k\":3,\"roughness\":\"neg\"},"
                            "\"glass\":{\"type\":\"dielectric\",\"eta\":\"zero\"}}," PLANE,
                       NULL);
    near_rgb(lambert_at(material(s, "m"), 0.5f, 0.5f), (ts_rgb){1, 1, 1}); /* (2, 1, 2) clamped */

    ts_texture_context c;
    ts_interaction si = hit(0.5f, 0.5f, &c);
    ts_bsdf a, b;
    ts_material_bsdf(material(s, "on"), &si, &c, &a);
    ts_material_bsdf(material(s, "on90"), &si, &c, &b);
    ts_vec3 wo = {0.3f, 0.1f, 0.9f}, wi = {-0.2f, 0.4f, 0.8f};
    ts_rgb fa = ts_bsdf_f(&a, wo, wi), fb = ts_bsdf_f(&b, wo, wi);
    assert_memory_equal(&fa, &fb, sizeof fa);

    ts_material_bsdf(material(s, "metal"), &si, &c, &a);
    assert_int_equal(a.n_bxdfs, 1);
    assert_true(ts_bsdf_flags(&a) & TS_BXDF_SPECULAR);

    ts_material_bsdf(material(s, "glass"), &si, &c, &a);
    assert_true(a.eta == TS_MATERIAL_ETA_MIN);
    ts_scene_destroy(s);
}

/* "texture_clamp": "nonnegative" (what a .pbrt file's materials get: pbrt-v3 clamps
 * textured colours at 0 only) keeps a reflectance of 2; an
 * uber opacity above 1 passes nothing through; the coupled plastic keeps [0, 1]. */
static void test_texture_clamp_nonnegative(void **state)
{
    (void)state;
    ts_scene *s = load(HEAD "\"textures\":{\"two\":{\"type\":\"scale\",\"tex1\":4,\"tex2\":[0.5,0.25,0]},"
                            "\"op\":{\"type\":\"scale\",\"tex1\":2,\"tex2\":0.75}},"
                            "\"materials\":{\"m\":{\"type\":\"diffuse\",\"texture_clamp\":\"nonnegative\","
                            "\"reflectance\":\"two\"},"
                            "\"u\":{\"type\":\"uber\",\"texture_clamp\":\"nonnegative\",\"diffuse\":0.5,"
                            "\"specular\":0,\"reflectance\":0,\"transmittance\":0,\"opacity\":\"op\"},"
                            "\"p\":{\"type\":\"plastic\",\"texture_clamp\":\"nonnegative\",\"diffuse\":\"two\","
                            "\"specular\":0}}," PLANE,
                       NULL);
    near_rgb(lambert_at(material(s, "m"), 0.5f, 0.5f), (ts_rgb){2, 1, 0});
    ts_texture_context c;
    ts_interaction si = hit(0.5f, 0.5f, &c);
    ts_bsdf b;
    ts_material_bsdf(material(s, "u"), &si, &c, &b);
    assert_int_equal(b.n_bxdfs, 1); /* no pass-through lobe for an opacity of 1.5 */
    ts_material_bsdf(material(s, "p"), &si, &c, &b);
    ts_vec3 n = {0, 0, 1};
    ts_rgb f = ts_bsdf_f(&b, n, n);
    assert_true(f.r <= 1.0f / (float)M_PI + 1e-6f && f.b == 0); /* clamped into [0, 1] */
    ts_scene_destroy(s);
    refused(HEAD "\"materials\":{\"m\":{\"type\":\"diffuse\",\"texture_clamp\":\"none\"}}," PLANE,
            "materials.m.texture_clamp");
}

/* A textured roughness may be smooth somewhere and rough elsewhere: the effects analysis
 * counts both lobes; a textured reflectance counts its lobe even where the constant would
 * be black. */
static void test_effects_of_textured_materials(void **state)
{
    (void)state;
    ts_scene *s = load(HEAD "\"textures\":{\"r\":{\"type\":\"checkerboard\",\"kind\":\"float\",\"tex1\":0,"
                            "\"tex2\":0.3}},\"materials\":{\"m\":{\"type\":\"conductor\",\"eta\":0.2,\"k\":3,"
                            "\"roughness\":\"r\"}}," PLANE,
                       NULL);
    assert_true(s->effects & TS_EFFECT_SPECULAR_REFLECTION);
    assert_true(s->effects & TS_EFFECT_GLOSSY);
    assert_false(s->effects & TS_EFFECT_LOBE_CHOICE); /* one lobe at every point */
    ts_scene_destroy(s);
    s = load(HEAD "\"textures\":{\"c\":{\"type\":\"constant\",\"value\":0}},"
                  "\"materials\":{\"m\":{\"type\":\"diffuse\",\"reflectance\":\"c\"}}," PLANE,
             NULL);
    assert_true(s->effects & TS_EFFECT_DIFFUSE);
    ts_scene_destroy(s);
}

/* An image map through JSON: a 2 × 1 float map (PFM) with scale 0.5, read at the two texel
 * centres with no footprint (the finest level, bilinear: exactly the texels). */
static void test_json_imagemap(void **state)
{
    (void)state;
    char dir[] = "/tmp/tessera-mattex-XXXXXX";
    assert_non_null(mkdtemp(dir));
    char path[256];
    snprintf(path, sizeof path, "%s/t.pfm", dir);
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    float px[2] = {0.25f, 1.5f};
    fprintf(f, "Pf\n2 1\n-1.0\n");
    fwrite(px, sizeof px, 1, f);
    fclose(f);
    ts_scene *s = load(HEAD "\"textures\":{\"img\":{\"type\":\"imagemap\",\"file\":\"t.pfm\",\"scale\":0.5,"
                            "\"wrap\":\"clamp\",\"trilinear\":true}},"
                            "\"materials\":{\"m\":{\"type\":\"diffuse\",\"reflectance\":\"img\"}}," PLANE,
                       dir);
    assert_non_null(s->texture_cache);
    const ts_material *m = material(s, "m");
    near_rgb(lambert_at(m, 0.25f, 0.5f), ts_rgb_gray(0.125f));
    near_rgb(lambert_at(m, 0.75f, 0.5f), ts_rgb_gray(0.75f));
    ts_scene_destroy(s);
    unlink(path);
    rmdir(dir);
}

/* The builder's texture calls, as the pbrt-v3 importer uses them, and its refusals. */
static void test_builder_textures(void **state)
{
    (void)state;
    ts_scene_builder *b = NULL;
    ts_error err = {0};
    assert_int_equal(ts_scene_builder_create(NULL, NULL, &b, &err), TS_OK);
    ts_texture_cache *cache = NULL, *again = NULL;
    assert_int_equal(ts_scene_builder_texture_cache(b, &cache, &err), TS_OK);
    assert_int_equal(ts_scene_builder_texture_cache(b, &again, &err), TS_OK);
    assert_ptr_equal(cache, again);
    assert_null(ts_scene_builder_base_dir(b));
    assert_non_null(ts_scene_builder_limits(b));

    ts_texture rgb_proto = ts_texture_constant_rgb((ts_rgb){0.1f, 0.2f, 0.3f});
    const ts_texture *rgb = NULL, *grey = NULL;
    assert_int_equal(ts_texture_make(ts_scene_builder_texture_arena(b), &rgb_proto, &rgb, &err), TS_OK);
    ts_texture grey_proto = ts_texture_constant_float(0.2f);
    assert_int_equal(ts_scene_builder_add_texture(b, &grey_proto, &grey, &err), TS_OK);

    ts_material m = {.type = TS_MATERIAL_PLASTIC,
                     .diffuse = {ts_rgb_gray(0), rgb},
                     .specular = {ts_rgb_gray(0), grey},
                     .roughness = {0, rgb}};
    assert_int_equal(ts_scene_builder_add_material(b, "bad", &m, NULL, &err), TS_ERR_INVALID);
    assert_string_equal(err.message, "roughness: expected a float texture, got an RGB one");
    m.roughness = (ts_material_float){0, grey};
    m.diffuse.value = ts_rgb_gray(7); /* ignored: the texture wins */
    uint32_t id;
    assert_int_equal(ts_scene_builder_add_material(b, "ok", &m, &id, &err), TS_OK);
    ts_material d = {
        .type = TS_MATERIAL_DIFFUSE, .reflectance = {ts_rgb_gray(0.5f), NULL}, .sigma_deg = {0, rgb}};
    assert_int_equal(ts_scene_builder_add_material(b, "d", &d, NULL, &err), TS_ERR_INVALID);
    assert_string_equal(err.message, "sigma: expected a float texture, got an RGB one");

    const ts_mipmap *map = NULL;
    ts_texture_image_options opt = {
        .n_channels = 3, .gamma = false, .scale = 1, .wrap = TS_TEXTURE_WRAP_REPEAT};
    assert_int_equal(ts_scene_builder_load_texture_image(b, "x.png", &opt, &map, &err), TS_ERR_INVALID);
    assert_non_null(strstr(err.message, "x.png"));
    assert_null(map);
    ts_scene_builder_destroy(b);
}

/* Refusals through JSON name the path. */
static void test_json_refusals(void **state)
{
    (void)state;
    refused(HEAD "\"materials\":{\"m\":{\"type\":\"diffuse\",\"reflectance\":\"nope\"}}," PLANE,
            "materials.m.reflectance: no texture named \"nope\" in 'textures'");
    refused(HEAD "\"textures\":{\"c\":{\"type\":\"constant\",\"value\":0.5}},"
                 "\"materials\":{\"m\":{\"type\":\"plastic\",\"roughness\":\"c\"}}," PLANE,
            "materials.m.roughness: texture \"c\" is an RGB texture; expected a float one");
    refused(HEAD "\"textures\":{\"a\":{\"type\":\"scale\",\"tex1\":\"b\"},\"b\":{\"type\":\"constant\"}},"
                 "\"materials\":{\"m\":{\"type\":\"diffuse\"}}," PLANE,
            "textures.a.tex1: no texture named \"b\" in 'textures' (defined before it)");
    refused(HEAD "\"textures\":{\"a\":{\"type\":\"constant\",\"kind\":\"float\"},"
                 "\"m\":{\"type\":\"mix\",\"amount\":[0.5,0.5,0.5]}},"
                 "\"materials\":{\"m\":{\"type\":\"diffuse\"}}," PLANE,
            "textures.m.amount: expected a finite number, got an array of 3");
    refused(HEAD
            "\"textures\":{\"a\":{\"type\":\"constant\",\"kind\":\"float\"},"
            "\"m\":{\"type\":\"mix\",\"tex1\":\"a\"}},\"materials\":{\"m\":{\"type\":\"diffuse\"}}," PLANE,
            "textures.m.tex1: texture \"a\" is a float texture; expected an RGB one");
    refused(HEAD "\"textures\":{\"u\":{\"type\":\"uv\",\"kind\":\"float\"}},\"materials\":{\"m\":{\"type\":"
                 "\"diffuse\"}}," PLANE,
            "textures.u.kind: a uv texture is RGB only");
    refused(HEAD
            "\"textures\":{\"w\":{\"type\":\"imagemap\",\"file\":\"w.png\"}},\"materials\":{\"m\":{\"type\":"
            "\"diffuse\"}}," PLANE,
            "textures.w.file: texture image 'w.png'");
    refused(HEAD "\"textures\":{\"f\":{\"type\":\"fbm\",\"octaves\":40}},\"materials\":{\"m\":{\"type\":"
                 "\"diffuse\"}}," PLANE,
            "textures.f.octaves: expected an integer in [0, 32]");
    refused(HEAD
            "\"textures\":{\"c\":{\"type\":\"checkerboard\",\"mapping\":{\"type\":\"planar\",\"uscale\":2}}},"
            "\"materials\":{\"m\":{\"type\":\"diffuse\"}}," PLANE,
            "textures.c.mapping.uscale: unknown key (allowed here: type, v1, v2, udelta, vdelta)");
    refused(HEAD "\"textures\":{\"c\":{\"type\":\"constant\"}},\"materials\":{\"m\":{\"type\":\"diffuse\","
                 "\"bumpmap\":\"c\"}}," PLANE,
            "materials.m.bumpmap: texture \"c\" is an RGB texture; expected a float one");
    refused(HEAD "\"materials\":{\"m\":{\"type\":\"diffuse\",\"bumpmap\":0.5}}," PLANE,
            "materials.m.bumpmap: expected the name of a float texture, got 0.5");
    refused(HEAD "\"textures\":{\"f\":{\"type\":\"fbm\",\"transform\":[{\"scale\":2}],"
                 "\"world_to_texture\":[1,0,0,0,0,1,0,0,0,0,1,0,0,0,0,1]}},\"materials\":{\"m\":{\"type\":"
                 "\"diffuse\"}}," PLANE,
            "textures.f.world_to_texture: give either 'transform' (texture → world) or 'world_to_texture', not "
            "both");
    refused(HEAD "\"textures\":{\"f\":{\"type\":\"fbm\",\"world_to_texture\":[1,0,0]}},"
                 "\"materials\":{\"m\":{\"type\":\"diffuse\"}}," PLANE,
            "textures.f.world_to_texture: expected an array of 16 numbers (row-major), got an array of 3");
}

/* "world_to_texture" is the solid lookup's matrix itself: an fbm given diag(2, 2, 2) as
 * world_to_texture is the fbm whose transform is scale 0.5 (texture → world), read at
 * the same points. */
static void test_json_world_to_texture(void **state)
{
    (void)state;
    const char *docs[2] = {
        HEAD "\"textures\":{\"f\":{\"type\":\"fbm\",\"kind\":\"float\",\"world_to_texture\":[2,0,0,0,0,2,0,0,0,"
             "0,2,0,0,0,0,1]}},\"materials\":{\"m\":{\"type\":\"diffuse\",\"reflectance\":\"f\"}}," PLANE,
        HEAD "\"textures\":{\"f\":{\"type\":\"fbm\",\"kind\":\"float\",\"transform\":[{\"scale\":0.5}]}},"
             "\"materials\":{\"m\":{\"type\":\"diffuse\",\"reflectance\":\"f\"}}," PLANE};
    float v[2][3];
    for (int k = 0; k < 2; k++) {
        ts_scene *s = NULL;
        ts_error err = {0};
        if (ts_scene_load_text(docs[k], strlen(docs[k]), NULL, "w2t", NULL, &s, &err)) fail_msg("%s", err.message);
        const ts_texture *t = s->materials[0].reflectance.tex;
        assert_non_null(t);
        for (int i = 0; i < 3; i++) {
            ts_texture_context c = {.p = {0.3f + 0.7f * (float)i, 0.2f, -0.4f * (float)i}};
            v[k][i] = ts_texture_eval_float(t, &c);
        }
        ts_scene_destroy(s);
    }
    for (int i = 0; i < 3; i++)
        assert_float_equal(v[0][i], v[1][i], 0);
    assert_true(v[0][0] != v[0][1]); /* the points see different noise: the comparison means something */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_json_checkerboard_reflectance),
        cmocka_unit_test(test_render_checkerboard),
        cmocka_unit_test(test_bump_linear),
        cmocka_unit_test(test_constant_material_ignores_context),
        cmocka_unit_test(test_textured_values_clamped),
        cmocka_unit_test(test_texture_clamp_nonnegative),
        cmocka_unit_test(test_effects_of_textured_materials),
        cmocka_unit_test(test_json_imagemap),
        cmocka_unit_test(test_builder_textures),
        cmocka_unit_test(test_json_refusals),
        cmocka_unit_test(test_json_world_to_texture),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
