/* test_alpha.c — alpha cut-outs (pbrt-v3's trianglemesh/plymesh "alpha" and "shadowalpha";
 * geometry/shape.h, geometry/accel.c, docs/design.md §4): what camera rays and shadow rays
 * see through a mesh with a checkerboard alpha, the two textures apart and together, through
 * object instances, an emitting cut-out mesh's light sampling, thread-count independence,
 * both front ends (their refusals, and a pbrt-v3 file against its `convert` document).
 *
 * The scenes are built so that every pixel's value is known exactly, not in expectation: an
 * orthographic camera looks down −z at a 16 × 16 film of 2 × 2 units (8 pixels a unit), box
 * filter of radius ½ (a pixel is the mean of its own samples). The alpha texture is pbrt-v3's
 * 2D checkerboard without antialiasing (aamode none: point-sampled) with s = t = 4/3 per unit,
 * so every check is 6 × 6 pixels with its edges on pixel edges, and each pixel lies in one
 * check: even checks (⌊s⌋ + ⌊t⌋ even) take tex1, odd ones tex2. tex1 is 0.3, not 1: pbrt-v3
 * cuts out only where alpha == 0, so 0.3 must be opaque (a `< 0.5` test fails here).
 *   - camera: a one-sided emitter of radiance 2 (black, so it only emits) at z = 1 in front
 *     of one of 0.5 at z = 0; `direct` adds the first hit's emission, nothing else (black
 *     materials reflect nothing), so a pixel is 2 where the front quad is hit and 0.5 where
 *     it is cut out.
 *   - shadow: a diffuse floor (R = 0.5) at z = 0 under a distant light travelling along
 *     (−1, 0, −1)/√2 with irradiance π√2, so an unshadowed floor pixel is R/π·E·cos 45° =
 *     0.5 exactly in real arithmetic; the occluder is a quad at z = 3 over x ∈ [1.5, 4.5],
 *     outside the camera's view, whose shadow falls on the view shifted by 3: the floor point
 *     (x, y) is lit exactly where the occluder is cut out for shadow rays at (x + 3, y).
 * One shadow ray per sample and no noise, so each pixel is compared to its value within
 * float rounding (1e-5 relative), and there is no false-failure rate to name (a Sobol sample
 * landing within rounding of a check edge could flip a sample: the edges are pixel edges,
 * which the scrambled samples do not meet; measured: none in any test). */
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

#include "film/film.h"
#include "integrators/effects.h"
#include "render/render.h"
#include "scene/scene.h"
#include "build/scene_builder.h"
#include "json/scene_json.h"
#include "load/scene_load.h"
#include "render_stats.h"
#include "scene_support.h"
#include "textures/texture.h"
#include "tmp_folder.h"

/* ---------------------------------------------------------------- helpers */

/* tests/scene_support.h's, under this file's names */
static ts_scene *load(const char *doc) { return ts_test_load_json(doc); }
static void refused(const char *doc, const char *want) { ts_test_json_refused(doc, want); }
static ts_film *render_threads(const ts_scene *s, int threads) { return ts_test_render(s, threads); }

static ts_film *render(const ts_scene *s) { return render_threads(s, 2); }

/* The checkerboard's parity at the point (x, y) of the view (s = t = 4/3·(· + 1.5), the
 * occluder's uv checks seen through its shift, and the front quad's). */
static bool even_check(double x, double y) { return ((int)floor(4.0 / 3 * (x + 1.5)) + (int)floor(4.0 / 3 * (y + 1.5))) % 2 == 0; }

/* The view point of pixel (px, py)'s centre. */
static double view_x(int px) { return -1 + (px + 0.5) / 8; }
static double view_y(int py) { return 1 - (py + 0.5) / 8; }

typedef float (*expect_fn)(int px, int py);

/* Every pixel's three channels against want(px, py), 1e-5 relative. */
static void expect_pixels(const char *what, const char *doc, expect_fn want)
{
    ts_scene *s = load(doc);
    ts_film *f = render(s);
    for (int py = 0; py < s->height; py++)
        for (int px = 0; px < s->width; px++) {
            ts_rgb got = ts_film_pixel_rgb(f, px, py);
            float w = want(px, py);
            if (fabsf(got.r - w) > 1e-5f * fmaxf(w, 1) || fabsf(got.g - w) > 1e-5f * fmaxf(w, 1) ||
                fabsf(got.b - w) > 1e-5f * fmaxf(w, 1))
                fail_msg("%s: pixel (%d, %d) is (%.7g, %.7g, %.7g), want %.7g", what, px, py, got.r, got.g, got.b, w);
        }
    ts_film_destroy(f);
    ts_scene_destroy(s);
}

/* ---------------------------------------------------------------- scenes */

#define VIEW                                                                                                       \
    "{\"tessera\":1,\"camera\":{\"type\":\"orthographic\",\"from\":[0,0,5],\"to\":[0,0,0],\"height\":2},"          \
    "\"film\":{\"width\":16,\"height\":16,\"filter\":{\"type\":\"box\"}},\"sampler\":{\"spp\":4},"
#define CHECKS                                                                                                     \
    "\"checks\":{\"type\":\"checkerboard\",\"kind\":\"float\",\"aamode\":\"none\","                                \
    "\"mapping\":{\"type\":\"uv\",\"uscale\":4,\"vscale\":4},\"tex1\":0.3,\"tex2\":0}"
/* A quad of side 3 centred at (cx, cy, cz) facing +z, uvs 0 … 1 across it. */
#define QUAD(cx, cy, cz)                                                                                           \
    "\"positions\":[" #cx "-1.5," #cy "-1.5," #cz ", " #cx "+1.5," #cy "-1.5," #cz ", " #cx "+1.5," #cy "+1.5," #cz \
    ", " #cx "-1.5," #cy "+1.5," #cz "],\"indices\":[0,1,2,0,2,3],\"uvs\":[0,0,1,0,1,1,0,1]"

/* JSON has no arithmetic: the quads spelt out. */
#define FRONT_QUAD "\"positions\":[-1.5,-1.5,1, 1.5,-1.5,1, 1.5,1.5,1, -1.5,1.5,1],\"indices\":[0,1,2,0,2,3],\"uvs\":[0,0,1,0,1,1,0,1]"
#define OBJ_QUAD "\"positions\":[-1.5,-1.5,0, 1.5,-1.5,0, 1.5,1.5,0, -1.5,1.5,0],\"indices\":[0,1,2,0,2,3],\"uvs\":[0,0,1,0,1,1,0,1]"
#define OCCLUDER_QUAD "\"positions\":[1.5,-1.5,3, 4.5,-1.5,3, 4.5,1.5,3, 1.5,1.5,3],\"indices\":[0,1,2,0,2,3],\"uvs\":[0,0,1,0,1,1,0,1]"
#define BIG_QUAD "\"positions\":[-3,-3,0, 3,-3,0, 3,3,0, -3,3,0],\"indices\":[0,1,2,0,2,3]"

/* The camera scene with the front quad's cut-out keys CUT (e.g. "\"alpha\":\"checks\","). */
static void camera_doc(char *buf, size_t n, const char *cut)
{
    snprintf(buf, n,
             VIEW "\"integrator\":{\"type\":\"direct\"},\"textures\":{" CHECKS "},"
                  "\"materials\":{\"black\":{\"type\":\"diffuse\",\"reflectance\":0}},"
                  "\"shapes\":[{\"type\":\"mesh\",%s\"emission\":2,\"material\":\"black\"," FRONT_QUAD "},"
                  "{\"type\":\"mesh\",\"emission\":0.5,\"material\":\"black\"," BIG_QUAD "}]}",
             cut);
}

/* The shadow scene with the occluder's cut-out keys CUT, rendered by `direct`; with media,
 * by volpath (max_depth 1) with the whole scene inside a surface-less sphere bounding a
 * clear medium (σ = 0: transmittance exactly 1), so every shadow ray is traced through
 * media and a boundary (volpath's ratio-tracking path) and the pixels stay the same. */
static void shadow_doc_in(char *buf, size_t n, bool media, const char *cut)
{
    snprintf(buf, n,
             VIEW "\"integrator\":{\"type\":\"%s\",\"max_depth\":1},\"textures\":{" CHECKS "},%s"
                  "\"lights\":[{\"type\":\"distant\",\"from\":[1,0,1],\"to\":[0,0,0],\"irradiance\":4.442882938158366}],"
                  "\"materials\":{\"white\":{\"type\":\"diffuse\",\"reflectance\":0.5}},"
                  "\"shapes\":[{\"type\":\"mesh\",%s\"material\":\"white\"," OCCLUDER_QUAD "},%s"
                  "{\"type\":\"mesh\",\"material\":\"white\"," BIG_QUAD "}]}",
             media ? "volpath" : "direct",
             media ? "\"media\":{\"clear\":{\"type\":\"homogeneous\",\"sigma_a\":[0,0,0],\"sigma_s\":[0,0,0]}}," : "",
             cut,
             media ? "{\"type\":\"sphere\",\"radius\":20,\"material\":null,\"medium\":{\"inside\":\"clear\"}}," : "");
}

static void shadow_doc(char *buf, size_t n, const char *cut) { shadow_doc_in(buf, n, false, cut); }

static float front_where_even(int px, int py) { return even_check(view_x(px), view_y(py)) ? 2.0f : 0.5f; }
static float front_everywhere(int px, int py) { (void)px, (void)py; return 2.0f; }
static float back_everywhere(int px, int py) { (void)px, (void)py; return 0.5f; }
static float lit_where_odd(int px, int py) { return even_check(view_x(px), view_y(py)) ? 0.0f : 0.5f; }
static float lit_everywhere(int px, int py) { (void)px, (void)py; return 0.5f; }
static float lit_nowhere(int px, int py) { (void)px, (void)py; return 0.0f; }

/* ---------------------------------------------------------------- camera rays */

/* Camera rays pass through the front quad exactly where alpha is 0 (odd checks) and stop
 * where it is 0.3; shadow_alpha alone leaves the quad whole to the camera ("visible but not
 * shadowing", its shadow side below); alpha 0 removes it from the view whatever
 * shadow_alpha says. */
static void test_camera_sees_through_cut_outs(void **state)
{
    (void)state;
    static char doc[4096];
    camera_doc(doc, sizeof doc, "\"alpha\":\"checks\",");
    expect_pixels("alpha checks", doc, front_where_even);
    camera_doc(doc, sizeof doc, "");
    expect_pixels("no alpha", doc, front_everywhere);
    camera_doc(doc, sizeof doc, "\"shadow_alpha\":\"checks\",");
    expect_pixels("shadow_alpha checks", doc, front_everywhere);
    camera_doc(doc, sizeof doc, "\"shadow_alpha\":0,");
    expect_pixels("shadow_alpha 0", doc, front_everywhere);
    camera_doc(doc, sizeof doc, "\"alpha\":0,\"shadow_alpha\":1,");
    expect_pixels("alpha 0", doc, back_everywhere);
    camera_doc(doc, sizeof doc, "\"alpha\":0.3,");
    expect_pixels("alpha 0.3", doc, front_everywhere);
}

/* An image alpha is looked up as pbrt-v3 looks it up without ray differentials: bilinearly
 * in the finest MIP level. A 4 × 4 float image whose left two columns are 0 and right two
 * 1, wrap clamp, across the front quad (s = u = (x + 1.5)/3): the bilinear value is 0
 * exactly where s·4 − ½ < 1 (both texels looked at are 0), s < 0.375, the world's
 * x < −0.375 — the pixel edge between columns 4 and 5; any coarser level (the 2 × 2 level
 * is 0, 1 per column pair, blended over wider texels; the 1 × 1 one 0.5) cuts out less or
 * nothing. */
static float image_cut(int px, int py)
{
    (void)py;
    return px <= 4 ? 0.5f : 2.0f;
}

static void test_image_alpha_finest_level(void **state)
{
    (void)state;
    unsigned char pfm[64 + 16 * 4];
    int n = snprintf((char *)pfm, 64, "Pf\n4 4\n-1.0\n");
    for (int i = 0; i < 16; i++) {
        float v = (i % 4) < 2 ? 0.0f : 1.0f;
        memcpy(pfm + n + 4 * i, &v, 4);
    }
    ts_tmp_write("half.pfm", pfm, (size_t)n + 64, NULL, 0);
    static char doc[4096];
    snprintf(doc, sizeof doc,
             VIEW "\"integrator\":{\"type\":\"direct\"},\"textures\":{\"img\":{\"type\":\"imagemap\",\"kind\":"
                  "\"float\",\"file\":\"half.pfm\",\"wrap\":\"clamp\"}},"
                  "\"materials\":{\"black\":{\"type\":\"diffuse\",\"reflectance\":0}},"
                  "\"shapes\":[{\"type\":\"mesh\",\"alpha\":\"img\",\"emission\":2,\"material\":\"black\"," FRONT_QUAD
                  "},{\"type\":\"mesh\",\"emission\":0.5,\"material\":\"black\"," BIG_QUAD "}]}");
    ts_scene *s = NULL;
    ts_error err = {0};
    if (ts_scene_load_text(doc, strlen(doc), ts_tmp_dir, "t", NULL, &s, &err)) fail_msg("%s", err.message);
    ts_film *f = render(s);
    for (int py = 0; py < 16; py++)
        for (int px = 0; px < 16; px++) {
            float got = ts_film_pixel_rgb(f, px, py).g, want = image_cut(px, py);
            if (fabsf(got - want) > 1e-5f) fail_msg("image alpha: pixel (%d, %d) is %.7g, want %.7g", px, py, got, want);
        }
    ts_film_destroy(f);
    ts_scene_destroy(s);
}

/* ---------------------------------------------------------------- shadow rays */

/* Shadow rays (pbrt-v3's IntersectP) test alpha and then shadow_alpha: the floor is lit
 * where the occluder's alpha is 0 when only alpha is given, where shadow_alpha is 0 when
 * only it is, and shadow_alpha 1 cannot restore the shadow alpha 0 removed (pbrt-v3 tests
 * both). */
static void test_shadows_through_cut_outs(void **state)
{
    (void)state;
    static char doc[4096];
    shadow_doc(doc, sizeof doc, "");
    expect_pixels("opaque occluder", doc, lit_nowhere);
    shadow_doc(doc, sizeof doc, "\"alpha\":\"checks\",");
    expect_pixels("alpha checks", doc, lit_where_odd);
    shadow_doc(doc, sizeof doc, "\"shadow_alpha\":\"checks\",");
    expect_pixels("shadow_alpha checks", doc, lit_where_odd);
    shadow_doc(doc, sizeof doc, "\"alpha\":\"checks\",\"shadow_alpha\":1,");
    expect_pixels("alpha checks, shadow_alpha 1", doc, lit_where_odd);
    shadow_doc(doc, sizeof doc, "\"shadow_alpha\":0,");
    expect_pixels("shadow_alpha 0 (visible, no shadow)", doc, lit_everywhere);
    shadow_doc(doc, sizeof doc, "\"alpha\":0,\"shadow_alpha\":1,");
    expect_pixels("alpha 0, shadow_alpha 1", doc, lit_everywhere);
    shadow_doc(doc, sizeof doc, "\"alpha\":1,\"shadow_alpha\":0.3,");
    expect_pixels("alpha 1, shadow_alpha 0.3", doc, lit_nowhere);
}

/* volpath's shadow rays through media and surface-less boundaries (transmittance by
 * ratio tracking, segment by segment) see the cut-outs as the surface shadow rays above
 * do: alpha and shadow_alpha alike. Camera at z = 5 outside the sphere, max_depth 1: a
 * floor pixel is its direct light, the same exact values. */
static void test_media_shadows_through_cut_outs(void **state)
{
    (void)state;
    static char doc[4096];
    static const struct { const char *cut; expect_fn want; } cases[] = {
        {"", lit_nowhere},
        {"\"alpha\":\"checks\",", lit_where_odd},
        {"\"shadow_alpha\":\"checks\",", lit_where_odd},
        {"\"alpha\":\"checks\",\"shadow_alpha\":1,", lit_where_odd},
        {"\"shadow_alpha\":0,", lit_everywhere},
        {"\"alpha\":0,\"shadow_alpha\":1,", lit_everywhere},
        {"\"alpha\":1,\"shadow_alpha\":0.3,", lit_nowhere},
    };
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        shadow_doc_in(doc, sizeof doc, true, cases[i].cut);
        ts_scene *s = load(doc);
        assert_true(s->effects & TS_EFFECT_MEDIA);
        ts_scene_destroy(s);
        char what[96];
        snprintf(what, sizeof what, "volpath through media, occluder %s", cases[i].cut[0] ? cases[i].cut : "opaque");
        expect_pixels(what, doc, cases[i].want);
    }
}

/* ---------------------------------------------------------------- instances */

/* Cut-outs work through object instances, and, as in pbrt-v3 (whose TransformedPrimitive
 * tests the object's own triangles), alpha is evaluated at the object-space point: a planar
 * mapping s = 2 + (4/3)·p_x of an object quad instanced under a translation by 0.75 in x
 * has its checks where (4/3)·(x − 0.75) + 2 says, one check over from where the world
 * point would put them. The instanced occluder casts the shadow of the direct one. */
static float instanced_planar(int px, int py)
{
    double x = view_x(px), y = view_y(py), ox = x - 0.75; /* object space */
    if (ox < -1.5) return 0.5f;                         /* left of the quad: the back emitter */
    bool even = ((int)floor(2 + 4.0 / 3 * ox) + (int)floor(2 + 4.0 / 3 * y)) % 2 == 0;
    return even ? 2.0f : 0.5f;
}

static void test_instanced_cut_outs(void **state)
{
    (void)state;
    static char doc[4096];
    snprintf(doc, sizeof doc,
             VIEW "\"integrator\":{\"type\":\"direct\"},\"textures\":{\"pchecks\":{\"type\":\"checkerboard\","
                  "\"kind\":\"float\",\"aamode\":\"none\",\"mapping\":{\"type\":\"planar\",\"v1\":[1.3333333333333333,0,0],"
                  "\"v2\":[0,1.3333333333333333,0],\"udelta\":2,\"vdelta\":2},\"tex1\":0.3,\"tex2\":0}},"
                  "\"materials\":{\"black\":{\"type\":\"diffuse\",\"reflectance\":0}},"
                  "\"objects\":{\"front\":{\"shapes\":[{\"type\":\"mesh\",\"alpha\":\"pchecks\",\"material\":\"black\","
                  OBJ_QUAD "}]}},\"instances\":[{\"object\":\"front\",\"transform\":[{\"translate\":[0.75,0,1]}]}],"
                  "\"shapes\":[{\"type\":\"mesh\",\"emission\":0.5,\"material\":\"black\"," BIG_QUAD "}]}");
    /* Objects cannot emit: the front quad is black (0) where hit, the back emitter 0.5. */
    ts_scene *s = load(doc);
    assert_int_equal(s->n_instances, 1);
    ts_film *f = render(s);
    for (int py = 0; py < 16; py++)
        for (int px = 0; px < 16; px++) {
            float want = instanced_planar(px, py) == 2.0f ? 0.0f : 0.5f, got = ts_film_pixel_rgb(f, px, py).g;
            if (fabsf(got - want) > 1e-5f) fail_msg("instanced planar: pixel (%d, %d) is %.7g, want %.7g", px, py, got, want);
        }
    ts_film_destroy(f);
    ts_scene_destroy(s);

    snprintf(doc, sizeof doc,
             VIEW "\"integrator\":{\"type\":\"direct\"},\"textures\":{" CHECKS "},"
                  "\"lights\":[{\"type\":\"distant\",\"from\":[1,0,1],\"to\":[0,0,0],\"irradiance\":4.442882938158366}],"
                  "\"materials\":{\"white\":{\"type\":\"diffuse\",\"reflectance\":0.5}},"
                  "\"objects\":{\"occ\":{\"shapes\":[{\"type\":\"mesh\",\"alpha\":\"checks\",\"material\":\"white\","
                  OBJ_QUAD "}]}},\"instances\":[{\"object\":\"occ\",\"transform\":[{\"translate\":[3,0,3]}]}],"
                  "\"shapes\":[{\"type\":\"mesh\",\"material\":\"white\"," BIG_QUAD "}]}");
    expect_pixels("instanced occluder", doc, lit_where_odd);
}

/* ---------------------------------------------------------------- emitters, threads */

/* An emitting quad (radiance 3, facing down, over x ∈ [1.5, 4.5] at z = 2: out of view)
 * lighting the floor, with the checkerboard alpha or without. */
static void emitter_doc(char *buf, size_t n, const char *integrator, const char *cut)
{
    snprintf(buf, n,
             VIEW "\"integrator\":%s,\"textures\":{" CHECKS "},"
                  "\"materials\":{\"white\":{\"type\":\"diffuse\",\"reflectance\":0.5}},"
                  "\"shapes\":[{\"type\":\"mesh\",%s\"emission\":3,\"material\":\"white\","
                  "\"positions\":[1.5,-1.5,2, 1.5,1.5,2, 4.5,1.5,2, 4.5,-1.5,2],\"indices\":[0,1,2,0,2,3],"
                  "\"uvs\":[0,0,0,1,1,1,1,0]},"
                  "{\"type\":\"mesh\",\"material\":\"white\"," BIG_QUAD "}]}",
             integrator, cut);
}

static bool same_pixels(const ts_film *a, const ts_film *b, int w, int h)
{
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            ts_rgb pa = ts_film_pixel_rgb(a, x, y), pb = ts_film_pixel_rgb(b, x, y);
            if (memcmp(&pa, &pb, sizeof pa) != 0) return false;
        }
    return true;
}

static double film_mean(const ts_film *f, int w, int h)
{
    double sum = 0;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) sum += ts_film_pixel_rgb(f, x, y).g;
    return sum / (w * h);
}

/* pbrt-v3 samples an area light over its whole triangles (Triangle::Sample, and
 * Shape::Pdf intersects with the alpha test off), and a shadow ray stops short of the
 * point sampled, so light sampling sees an emitting cut-out mesh as if it had no alpha:
 * with light sampling only, the floor is the same bit for bit with and without alpha. BSDF
 * sampling finds emission only where a ray stops, not through the cut-outs: its image is
 * darker (the MIS combination of the two is pbrt-v3's, in between). */
static void test_emitter_light_sampling(void **state)
{
    (void)state;
    static char a[4096], b[4096];
    emitter_doc(a, sizeof a, "{\"type\":\"direct\",\"sampling\":\"light\"}", "\"alpha\":\"checks\",");
    emitter_doc(b, sizeof b, "{\"type\":\"direct\",\"sampling\":\"light\"}", "");
    ts_scene *sa = load(a), *sb = load(b);
    ts_film *fa = render(sa), *fb = render(sb);
    assert_true(film_mean(fa, 16, 16) > 0.01);
    assert_true(same_pixels(fa, fb, 16, 16));
    ts_film_destroy(fa);
    ts_film_destroy(fb);
    ts_scene_destroy(sa);
    ts_scene_destroy(sb);

    emitter_doc(a, sizeof a, "{\"type\":\"direct\",\"sampling\":\"bsdf\"}", "\"alpha\":\"checks\",");
    emitter_doc(b, sizeof b, "{\"type\":\"direct\",\"sampling\":\"bsdf\"}", "");
    sa = load(a), sb = load(b);
    fa = render(sa), fb = render(sb);
    double ma = film_mean(fa, 16, 16), mb = film_mean(fb, 16, 16);
    /* Half the emitter's area is cut out: about half the light (the checks are not equally
     * bright seen from the floor); 0.3 … 0.7 holds for any arrangement of the 4 × 4 checks
     * that cuts 8 of them, far outside the 16-pixel, 4-sample noise (each pixel's relative
     * standard error here is below 0.5, the mean's below 0.03). */
    if (!(ma > 0.3 * mb && ma < 0.7 * mb)) fail_msg("BSDF sampling: %g with alpha, %g without", ma, mb);
    ts_film_destroy(fa);
    ts_film_destroy(fb);
    ts_scene_destroy(sa);
    ts_scene_destroy(sb);
}

/* BSDF sampling of the cut-out emitter estimates the light of its opaque part only: the
 * same expectation as light sampling of the eight opaque checks made separate quads
 * without alpha (a different estimator, so the two agree only statistically). K = 8
 * independent renders (seeds) of each at 16 spp, compared by Welch's t over 16 blocks of
 * 4 × 4 pixels and the whole image (tests/render_stats.h), Bonferroni at α = 1e-3: correct
 * code fails with probability at most 1e-3 (block means of 256 samples: normal enough).
 * With the whole emitter instead (alpha ignored by BSDF rays) the image is about twice as
 * bright: image t ≈ 89. */
static void test_emitter_bsdf_sees_opaque_part(void **state)
{
    (void)state;
    static char a[4096], b[8192];
    emitter_doc(a, sizeof a, "{\"type\":\"direct\",\"sampling\":\"bsdf\"}", "\"alpha\":\"checks\",");
    /* The even checks (i + j even) of the 4 × 4 over x ∈ [1.5, 4.5], y ∈ [-1.5, 1.5]. */
    char quads[6000] = "";
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) {
            if ((i + j) % 2) continue;
            double x0 = 1.5 + 0.75 * i, x1 = x0 + 0.75, y0 = -1.5 + 0.75 * j, y1 = y0 + 0.75;
            char q[400];
            snprintf(q, sizeof q,
                     "{\"type\":\"mesh\",\"emission\":3,\"material\":\"white\",\"positions\":[%g,%g,2, %g,%g,2, "
                     "%g,%g,2, %g,%g,2],\"indices\":[0,1,2,0,2,3]},",
                     x0, y0, x0, y1, x1, y1, x1, y0);
            strcat(quads, q);
        }
    snprintf(b, sizeof b,
             VIEW "\"integrator\":{\"type\":\"direct\",\"sampling\":\"light\"},"
                  "\"materials\":{\"white\":{\"type\":\"diffuse\",\"reflectance\":0.5}},"
                  "\"shapes\":[%s{\"type\":\"mesh\",\"material\":\"white\"," BIG_QUAD "}]}",
             quads);
    ts_scene *sa = load(a), *sb = load(b);
    ts_rs_blocks ra, rb;
    ts_rs_render(sa, TS_SAMPLER_SOBOL, 100, 8, 16, 4, &ra);
    ts_rs_render(sb, TS_SAMPLER_SOBOL, 200, 8, 16, 4, &rb);
    assert_true(rb.image_mean > 0.01);
    ts_rs_result r = ts_rs_compare(&ra, &rb, 0);
    if (!ts_rs_passes(&r, ra.n, 1e-3))
        fail_msg("BSDF-sampled cut-out emitter %.5g ± %.2g against its opaque checks %.5g ± %.2g (block %d: t %.2f, "
                 "p %.2g; image t %.2f)",
                 ra.image_mean, ra.image_se, rb.image_mean, rb.image_se, r.block, r.t, r.p, r.image_t);
    ts_scene_destroy(sa);
    ts_scene_destroy(sb);
}

/* Bit-identical pixels whatever the thread count, with a cut-out emitter, a cut-out
 * occluder and the path integrator's MIS (the filters are pure functions of ray and hit). */
static void test_threads_bit_identical(void **state)
{
    (void)state;
    static char doc[4096];
    emitter_doc(doc, sizeof doc, "{\"type\":\"path\",\"max_depth\":4}", "\"alpha\":\"checks\",\"shadow_alpha\":\"checks\",");
    ts_scene *s = load(doc);
    ts_film *f1 = render_threads(s, 1), *f2 = render_threads(s, 2), *f3 = render_threads(s, 3);
    assert_true(film_mean(f1, 16, 16) > 0.01);
    assert_true(same_pixels(f1, f2, 16, 16));
    assert_true(same_pixels(f1, f3, 16, 16));
    ts_film_destroy(f1);
    ts_film_destroy(f2);
    ts_film_destroy(f3);
    ts_scene_destroy(s);
}

/* ---------------------------------------------------------------- JSON refusals, builder */

static void test_json_refusals(void **state)
{
    (void)state;
    static char doc[4096];
    camera_doc(doc, sizeof doc, "\"alpha\":2,");
    refused(doc, "shapes[0].alpha: expected a number in [0, 1], got 2");
    camera_doc(doc, sizeof doc, "\"shadow_alpha\":-0.5,");
    refused(doc, "shapes[0].shadow_alpha: expected a number in [0, 1], got -0.5");
    camera_doc(doc, sizeof doc, "\"alpha\":\"nope\",");
    refused(doc, "shapes[0].alpha: no texture named \"nope\" in 'textures' (defined before it)");
    camera_doc(doc, sizeof doc, "\"alpha\":[0, 1],");
    refused(doc, "shapes[0].alpha: expected a number in [0, 1], got an array of 2");
    snprintf(doc, sizeof doc,
             VIEW "\"textures\":{\"c\":{\"type\":\"constant\",\"value\":[1,0,0]}},"
                  "\"materials\":{\"m\":{\"type\":\"diffuse\"}},"
                  "\"shapes\":[{\"type\":\"mesh\",\"alpha\":\"c\",\"material\":\"m\"," FRONT_QUAD "}]}");
    refused(doc, "shapes[0].alpha: texture \"c\" is an RGB texture; expected a float one");
    snprintf(doc, sizeof doc,
             VIEW "\"materials\":{\"m\":{\"type\":\"diffuse\"}},"
                  "\"shapes\":[{\"type\":\"sphere\",\"radius\":1,\"alpha\":0,\"material\":\"m\"}]}");
    ts_scene *s = NULL;
    ts_error err = {0};
    assert_int_not_equal(ts_scene_load_text(doc, strlen(doc), NULL, "t", NULL, &s, &err), TS_OK);
    if (!strstr(err.message, "shapes[0]") || !strstr(err.message, "alpha"))
        fail_msg("a sphere's alpha: %s", err.message);
}

/* The builder's own checks, whichever front end calls it. */
static void test_builder_refusals(void **state)
{
    (void)state;
    ts_scene_builder *b = NULL;
    ts_error err = {0};
    assert_int_equal(ts_scene_builder_create(NULL, NULL, &b, &err), TS_OK);
    ts_material m = {0};
    m.type = TS_MATERIAL_DIFFUSE;
    m.reflectance = ts_material_rgb_gray(0.5f);
    uint32_t mid;
    assert_int_equal(ts_scene_builder_add_material(b, "m", &m, &mid, &err), TS_OK);
    ts_texture proto = ts_texture_constant_float(0), proto_rgb = ts_texture_constant_rgb(ts_rgb_gray(0));
    const ts_texture *zero, *rgb;
    assert_int_equal(ts_scene_builder_add_texture(b, &proto, &zero, &err), TS_OK);
    assert_int_equal(ts_scene_builder_add_texture(b, &proto_rgb, &rgb, &err), TS_OK);
    ts_shape_desc d = {0};
    d.type = TS_SHAPE_SPHERE;
    d.material = mid;
    d.to_world = ts_xform_identity();
    d.sphere.radius = 1;
    d.alpha = zero;
    assert_int_equal(ts_scene_builder_add_shape(b, &d, NULL, &err), TS_ERR_INVALID);
    assert_string_equal(err.message, "alpha: only meshes take alpha textures (as pbrt-v3's trianglemesh and plymesh)");
    static const float p[] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    static const uint32_t idx[] = {0, 1, 2};
    d = (ts_shape_desc){0};
    d.type = TS_SHAPE_MESH;
    d.material = mid;
    d.to_world = ts_xform_identity();
    d.mesh = (ts_mesh){3, 1, p, NULL, NULL, idx};
    d.shadow_alpha = rgb;
    assert_int_equal(ts_scene_builder_add_shape(b, &d, NULL, &err), TS_ERR_INVALID);
    assert_string_equal(err.message, "shadow_alpha: expected a float texture, got an RGB one");
    ts_scene_counts c;
    ts_scene_builder_counts(b, &c);
    assert_int_equal(c.shapes, 0); /* nothing half-added */
    d.shadow_alpha = zero;
    assert_int_equal(ts_scene_builder_add_shape(b, &d, NULL, &err), TS_OK);
    ts_scene_builder_destroy(b);
}

/* ---------------------------------------------------------------- pbrt-v3 */

typedef struct warnings {
    int n;
    char last[TS_ERROR_MAX + 64];
} warnings;

static void on_warning(void *ctx, const char *msg)
{
    warnings *w = ctx;
    w->n++;
    snprintf(w->last, sizeof w->last, "%s", msg);
}

#define PBRT_HEAD                                                                                                  \
    "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"orthographic\" \"float screenwindow\" [-1 1 -1 1]\n"                      \
    "Film \"image\" \"integer xresolution\" 16 \"integer yresolution\" 16\nPixelFilter \"box\"\n"                  \
    "Sampler \"sobol\" \"integer pixelsamples\" 4\nIntegrator \"directlighting\"\nWorldBegin\n"                     \
    "Texture \"checks\" \"float\" \"checkerboard\" \"float uscale\" 4 \"float vscale\" 4 \"float tex1\" 0.3 "       \
    "\"float tex2\" 0 \"string aamode\" \"none\"\n"                                                                \
    "Texture \"red\" \"spectrum\" \"constant\" \"rgb value\" [1 0 0]\n"
#define PBRT_QUAD(z)                                                                                               \
    "\"point P\" [-1.5 -1.5 " #z " 1.5 -1.5 " #z " 1.5 1.5 " #z " -1.5 1.5 " #z "] \"integer indices\" [0 1 2 0 2 3] " \
    "\"float uv\" [0 0 1 0 1 1 0 1]"

static void pbrt_refused(const char *shape_line, const char *want)
{
    char text[4096];
    snprintf(text, sizeof text, PBRT_HEAD "%s\nWorldEnd\n", shape_line);
    ts_scene *s = NULL;
    ts_error err = {0};
    warnings w = {0};
    assert_int_not_equal(ts_scene_load_pbrt_text(text, strlen(text), NULL, "t.pbrt", NULL, on_warning, &w, &s, &err),
                         TS_OK);
    assert_null(s);
    if (strcmp(err.message, want) != 0) fail_msg("got      %s\nexpected %s", err.message, want);
}

static ts_scene *pbrt_load(const char *body, warnings *w)
{
    char text[4096];
    snprintf(text, sizeof text, PBRT_HEAD "%s\nWorldEnd\n", body);
    ts_scene *s = NULL;
    ts_error err = {0};
    if (ts_scene_load_pbrt_text(text, strlen(text), NULL, "t.pbrt", NULL, on_warning, w, &s, &err))
        fail_msg("%s", err.message);
    return s;
}

/* Bad alpha parameters: one sentence naming the file, line and column, the shape and the
 * parameter; nothing is made. */
static void test_pbrt_refusals(void **state)
{
    (void)state;
    pbrt_refused("Shape \"trianglemesh\" \"texture alpha\" \"nope\" " PBRT_QUAD(1),
                 "t.pbrt:10:22: Shape \"trianglemesh\": \"texture alpha\" names texture \"nope\", which is not defined here");
    pbrt_refused("Shape \"trianglemesh\" \"texture shadowalpha\" \"red\" " PBRT_QUAD(1),
                 "t.pbrt:10:22: Shape \"trianglemesh\": \"texture shadowalpha\" names the spectrum texture \"red\": "
                 "shadowalpha takes a float texture");
    pbrt_refused("Shape \"trianglemesh\" \"float alpha\" 2 " PBRT_QUAD(1),
                 "t.pbrt:10:22: Shape \"trianglemesh\": \"float alpha\" must be in [0, 1], got 2");
    pbrt_refused("Shape \"trianglemesh\" \"float alpha\" [0 1] " PBRT_QUAD(1),
                 "t.pbrt:10:22: Shape \"trianglemesh\": \"float alpha\" expects 1 value, got 2");
    pbrt_refused("Shape \"trianglemesh\" \"rgb alpha\" [0 0 0] " PBRT_QUAD(1),
                 "t.pbrt:10:22: Shape \"trianglemesh\": \"rgb alpha\" expects a float in [0, 1] or a float texture "
                 "(\"texture alpha\")");
}

/* pbrt-v3's volpath traces its shadow rays with Scene::Intersect (VisibilityTester::Tr),
 * which tests alpha and never shadowalpha: under volpath a mesh's shadowalpha is left out
 * with a warning at its file:line:column, alpha kept; under directlighting both are kept. */
static void test_pbrt_volpath_shadowalpha(void **state)
{
    (void)state;
    const char *body = "Shape \"trianglemesh\" \"texture alpha\" \"checks\" \"texture shadowalpha\" \"checks\" " PBRT_QUAD(1);
    char head[2048], text[4096];
    snprintf(head, sizeof head, "%s", PBRT_HEAD);
    char *at = strstr(head, "\"directlighting\"");
    assert_non_null(at);
    *at = 0;
    snprintf(text, sizeof text, "%s\"volpath\"%s%s\nWorldEnd\n", head, at + strlen("\"directlighting\""), body);
    ts_scene *s = NULL;
    ts_error err = {0};
    warnings w = {0};
    if (ts_scene_load_pbrt_text(text, strlen(text), NULL, "t.pbrt", NULL, on_warning, &w, &s, &err))
        fail_msg("%s", err.message);
    assert_int_equal(w.n, 1);
    if (!strstr(w.last, "t.pbrt:10:") || !strstr(w.last, "\"texture shadowalpha\" is not used: pbrt-v3's volpath"))
        fail_msg("warning: %s", w.last);
    assert_non_null(s->shapes[0].alpha);
    assert_null(s->shapes[0].shadow_alpha);
    ts_scene_destroy(s);
    w = (warnings){0};
    s = pbrt_load(body, &w);
    assert_int_equal(w.n, 0);
    assert_non_null(s->shapes[0].shadow_alpha);
    ts_scene_destroy(s);
}

/* pbrt-v3's CreateTriangleMeshShape: "float alpha" 0 cuts out the whole mesh (left out when
 * it does not emit: nothing of it shows or shadows; kept as an emitter that light sampling
 * still finds); other values leave it opaque, those in (0, 1) with a warning; a sphere's
 * alpha is an unused parameter, as in pbrt-v3. */
static void test_pbrt_constants(void **state)
{
    (void)state;
    warnings w = {0};
    ts_scene *s = pbrt_load("Shape \"trianglemesh\" \"float alpha\" 0 " PBRT_QUAD(1), &w);
    assert_int_equal(s->n_shapes, 0);
    assert_int_equal(w.n, 1);
    assert_non_null(strstr(w.last, "\"float alpha\" is 0: the shape is cut out entirely"));
    ts_scene_destroy(s);

    w = (warnings){0};
    s = pbrt_load("AttributeBegin AreaLightSource \"diffuse\" \"rgb L\" [2 2 2]\n"
                  "Shape \"trianglemesh\" \"float alpha\" 0 " PBRT_QUAD(1) "\nAttributeEnd",
                  &w);
    assert_int_equal(w.n, 0);
    assert_int_equal(s->n_shapes, 1);
    assert_int_equal(s->n_lights, 1); /* the quad's two triangles: one rectangle light (design.md §4) */
    assert_non_null(s->shapes[0].alpha);
    ts_film *f = render(s);
    for (int py = 0; py < 16; py++)
        for (int px = 0; px < 16; px++)
            if (ts_film_pixel_rgb(f, px, py).g != 0) fail_msg("pixel (%d, %d) sees the cut-out emitter", px, py);
    ts_film_destroy(f);
    ts_scene_destroy(s);

    w = (warnings){0};
    s = pbrt_load("Shape \"trianglemesh\" \"float alpha\" 0.5 \"float shadowalpha\" 1 " PBRT_QUAD(1), &w);
    assert_int_equal(w.n, 1);
    assert_non_null(strstr(w.last, "\"float alpha\" is 0.5: pbrt-v3 cuts out only where alpha is exactly 0"));
    assert_int_equal(s->n_shapes, 1);
    assert_null(s->shapes[0].alpha);
    assert_null(s->shapes[0].shadow_alpha);
    ts_scene_destroy(s);

    /* "texture alpha" naming a "constant" float texture: its value, here 0. */
    w = (warnings){0};
    s = pbrt_load("Texture \"none\" \"float\" \"constant\" \"float value\" 0\n"
                  "AttributeBegin AreaLightSource \"diffuse\" \"rgb L\" [2 2 2]\n"
                  "Shape \"trianglemesh\" \"texture alpha\" \"none\" " PBRT_QUAD(1) "\nAttributeEnd",
                  &w);
    assert_int_equal(w.n, 0);
    assert_int_equal(s->n_shapes, 1);
    assert_non_null(s->shapes[0].alpha);
    ts_scene_destroy(s);

    w = (warnings){0};
    s = pbrt_load("Shape \"sphere\" \"float alpha\" 0", &w);
    assert_int_equal(s->n_shapes, 1);
    assert_int_equal(w.n, 1);
    assert_non_null(strstr(w.last, "alpha"));
    ts_scene_destroy(s);
}

/* A pbrt-v3 file with a textured alpha on a trianglemesh and a textured shadowalpha on a
 * plymesh renders what the camera test expects, and `tessera convert`'s document (with its
 * "alpha" and "shadow_alpha" keys) renders the same pixels bit for bit. */
static void test_pbrt_and_convert(void **state)
{
    (void)state;
    static const char ply[] = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                              "property float z\nproperty float u\nproperty float v\nelement face 2\n"
                              "property list uchar int vertex_indices\nend_header\n"
                              "1.5 -1.5 3 0 0\n4.5 -1.5 3 1 0\n4.5 1.5 3 1 1\n1.5 1.5 3 0 1\n3 0 1 2\n3 0 2 3\n";
    ts_tmp_write("occ.ply", ply, strlen(ply), NULL, 0);
    char text[4096];
    snprintf(text, sizeof text,
             PBRT_HEAD "LightSource \"distant\" \"point from\" [1 0 1] \"point to\" [0 0 0] \"rgb L\" [3.14159265 "
                       "3.14159265 3.14159265]\n"
                       "AttributeBegin Material \"matte\" \"rgb Kd\" [0 0 0]\n"
                       "  AreaLightSource \"diffuse\" \"rgb L\" [2 2 2]\n"
                       "  Shape \"trianglemesh\" \"texture alpha\" \"checks\" " PBRT_QUAD(1) "\nAttributeEnd\n"
                       "AttributeBegin Material \"matte\" \"rgb Kd\" [0.5 0.5 0.5]\n"
                       "  Shape \"plymesh\" \"string filename\" \"occ.ply\" \"texture shadowalpha\" \"checks\"\n"
                       "  Shape \"trianglemesh\" \"point P\" [-3 -3 0 3 -3 0 3 3 0 -3 3 0] \"integer indices\" [0 1 2 "
                       "0 2 3]\nAttributeEnd\nWorldEnd\n");
    char path[512];
    ts_tmp_write("cut.pbrt", text, strlen(text), path, sizeof path);
    ts_scene *a = NULL, *b = NULL;
    ts_error err = {0};
    warnings w = {0};
    if (ts_scene_load_path(path, NULL, on_warning, &w, &a, &err)) fail_msg("%s", err.message);
    assert_int_equal(w.n, 0);
    char *json = NULL;
    size_t len = 0;
    if (ts_scene_convert_pbrt_path(path, NULL, NULL, NULL, &json, &len, &err)) fail_msg("%s", err.message);
    assert_non_null(strstr(json, "\"alpha\":\t\"checks\""));
    assert_non_null(strstr(json, "\"shadow_alpha\":\t\"checks\""));
    if (ts_scene_load_text(json, len, ts_tmp_dir, "cut", NULL, &b, &err)) fail_msg("%s", err.message);
    free(json);
    ts_film *fa = render(a), *fb = render(b);
    assert_true(same_pixels(fa, fb, 16, 16));
    /* The front quad: 2 where its alpha is 0.3, else the floor, which the plymesh shadows
     * where its shadowalpha is 0.3 and not where it is 0 (floor lit: 0.5·(π/π)·cos 45°,
     * plus the front emitter's light, which the camera test has no floor for, so only the
     * front pixels are exact here). */
    for (int py = 0; py < 16; py++)
        for (int px = 0; px < 16; px++) {
            /* pbrt-v3's camera space is left-handed: LookAt from +z puts world −x on the right. */
            float got = ts_film_pixel_rgb(fa, px, py).g;
            bool even = even_check(-view_x(px), view_y(py));
            if (even && fabsf(got - 2) > 2e-5f)
                fail_msg("pbrt-v3 front quad: pixel (%d, %d) is %.7g, want 2", px, py, got);
            if (!even && !(got < 1.5f))
                fail_msg("pbrt-v3 front quad: pixel (%d, %d) is %.7g: the cut-out shows", px, py, got);
        }
    ts_film_destroy(fa);
    ts_film_destroy(fb);
    ts_scene_destroy(a);
    ts_scene_destroy(b);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_camera_sees_through_cut_outs),
        cmocka_unit_test(test_image_alpha_finest_level),
        cmocka_unit_test(test_shadows_through_cut_outs),
        cmocka_unit_test(test_media_shadows_through_cut_outs),
        cmocka_unit_test(test_instanced_cut_outs),
        cmocka_unit_test(test_emitter_light_sampling),
        cmocka_unit_test(test_emitter_bsdf_sees_opaque_part),
        cmocka_unit_test(test_threads_bit_identical),
        cmocka_unit_test(test_json_refusals),
        cmocka_unit_test(test_builder_refusals),
        cmocka_unit_test(test_pbrt_refusals),
        cmocka_unit_test(test_pbrt_constants),
        cmocka_unit_test(test_pbrt_volpath_shadowalpha),
        cmocka_unit_test(test_pbrt_and_convert),
    };
    return cmocka_run_group_tests(tests, ts_tmp_group_setup, ts_tmp_group_teardown);
}
