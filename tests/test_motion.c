/* test_motion.c — motion blur (docs/design.md §4 "motion", core/animated_transform.h,
 * geometry/accel.h): closed-form images of a square sliding across a pixel row (camera
 * rays), of its shadow sliding across a floor (shadow rays keep the camera ray's time) and
 * of a camera sliding past a still square; the shutter's edges; scenes whose motion is none
 * or whose shutter is shut render bit for bit as the static scene; a rotating object at a
 * time against the static object at that time's matrix; the pbrt-v3 front end (two CTMs,
 * ActiveTransform, TransformTimes, the camera's shutter, convert) and its refusals. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "integrators/effects.h"
#include "json/scene_json.h"
#include "load/scene_load.h"
#include "render/render.h"
#include "tmp_folder.h"

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
    if (strcmp(err.message, sentence)) fprintf(stderr, "got:      %s\nexpected: %s\n", err.message, sentence);
    assert_string_equal(err.message, sentence);
}

typedef struct warnings {
    int n;
    char all[4096];
} warnings;

static void on_warning(void *ctx, const char *msg)
{
    warnings *w = ctx;
    w->n++;
    size_t l = strlen(w->all);
    snprintf(w->all + l, sizeof w->all - l, "%s\n", msg);
}

static ts_scene *load_pbrt(const char *text, warnings *w)
{
    ts_scene *s = NULL;
    ts_error err = {0};
    if (ts_scene_load_pbrt_text(text, strlen(text), NULL, "t.pbrt", NULL, on_warning, w, &s, &err))
        fail_msg("%s", err.message);
    return s;
}

static void expect_pbrt_error(const char *text, const char *sentence)
{
    ts_scene *s = NULL;
    ts_error err = {0};
    warnings w = {0};
    assert_int_not_equal(ts_scene_load_pbrt_text(text, strlen(text), NULL, "t.pbrt", NULL, on_warning, &w, &s, &err),
                         TS_OK);
    assert_null(s);
    if (strcmp(err.message, sentence)) fprintf(stderr, "got:      %s\nexpected: %s\n", err.message, sentence);
    assert_string_equal(err.message, sentence);
}

static ts_film *render(const ts_scene *s, int spp, int threads)
{
    ts_error err = {0};
    ts_film *f = ts_film_create(s->width, s->height, 0, 0, s->width, s->height, &err);
    ts_render_stats stats = {0};
    ts_render_request req = {s, s->integrator.type, f, 0, (uint32_t)spp, threads, NULL, NULL, NULL, false};
    assert_int_equal(ts_render(&req, &stats, &err), TS_OK);
    assert_int_equal(stats.counters.nonfinite, 0);
    return f;
}

/* The document's independent sampler made Sobol (in place). */
static void to_sobol(char *doc)
{
    char *p = strstr(doc, "\"independent\"");
    assert_non_null(p);
    memcpy(p, "\"sobol\"", 7);
    memmove(p + 7, p + 13, strlen(p + 13) + 1);
}

static bool films_equal(const ts_film *a, const ts_film *b)
{
    return a->width == b->width && a->height == b->height &&
           memcmp(a->pixels, b->pixels, sizeof *a->pixels * (size_t)a->width * (size_t)a->height) == 0;
}

/* ∫ over the shutter of the overlap of pixel column [a, a + 1] with the interval
 * [c + v·τ, c + v·τ + w], τ the motion's time clamped to [0, 1], divided by the shutter's
 * length: a column's expected covered fraction. The integrand is piecewise linear; the
 * midpoint rule on 2·10⁵ steps is exact to ~1e-10 here. */
static double coverage(double a, double c, double w, double v, double s0, double s1)
{
    if (s1 == s0) {
        double tau = fmin(fmax(s0, 0), 1), x0 = c + v * tau;
        return fmax(0, fmin(a + 1, x0 + w) - fmax(a, x0));
    }
    const int n = 200000;
    double sum = 0;
    for (int k = 0; k < n; k++) {
        double t = s0 + (s1 - s0) * (k + 0.5) / n, tau = fmin(fmax(t, 0), 1), x0 = c + v * tau;
        sum += fmax(0, fmin(a + 1, x0 + w) - fmax(a, x0));
    }
    return sum / n;
}

/* Every pixel of an 8 × 4 film whose columns x ∈ [−4 + i, −3 + i] see 1 where nothing is in
 * the way and 0 (a black surface, or a shadow on a floor of radiance l0) where it is, under
 * an independent sampler: each sample is l0·Bernoulli(1 − coverage), so a pixel's mean has
 * σ = l0·√(p(1 − p)/N). Bound 5σ per pixel (+1e-6 for float sums): with 32 pixels a
 * false-failure rate of 32 · 5.7e-7 ≈ 2e-5 (normal approximation, N = 4096). */
static void check_columns(const ts_film *f, double l0, double c, double w, double v, double s0, double s1,
                          const char *what)
{
    const double n = 4096;
    for (int y = 0; y < f->height; y++)
        for (int x = 0; x < f->width; x++) {
            double p = 1 - coverage(-4 + x, c, w, v, s0, s1);
            double sigma = l0 * sqrt(p * (1 - p) / n);
            double m = ts_film_pixel_rgb(f, x, y).g;
            if (!(fabs(m - l0 * p) <= 5 * sigma + 1e-6))
                fail_msg("%s: pixel (%d, %d) %.6f, expected %.6f (σ %.2g, shutter [%g, %g])", what, x, y, m, l0 * p,
                         sigma, s0, s1);
        }
}

#define SLIDE_HEAD                                                                                                   \
    "{\"tessera\":1,\"camera\":{\"type\":\"orthographic\",\"from\":[0,0,10],\"to\":[0,0,0],\"up\":[0,1,0],"           \
    "\"height\":4%s},\"film\":{\"width\":8,\"height\":4,\"filter\":{\"type\":\"box\",\"radius\":0.5}},"                \
    "\"sampler\":{\"type\":\"independent\",\"spp\":4096,\"seed\":7},\"integrator\":{\"type\":\"path\",\"max_depth\":1},"  \
    "\"materials\":{\"black\":{\"type\":\"diffuse\",\"reflectance\":0}},"
#define LIGHTS "\"lights\":[{\"type\":\"infinite\",\"radiance\":1}]}"
#define SQUARE(x0, x1, z)                                                                                             \
    "{\"type\":\"mesh\",\"positions\":[" #x0 ",-3," #z "," #x1 ",-3," #z "," #x1 ",3," #z "," #x0 ",3," #z "],"       \
    "\"indices\":[0,1,2,0,2,3],\"material\":\"black\""

/* A black square x ∈ [−4, −2.5] moving +6 over [0, 1] in front of a white environment. */
static void slide_camera_rays(void **state)
{
    (void)state;
    const double shutters[][2] = {{0, 1}, {0.25, 0.5}, {-0.5, 0.5}, {0.75, 2}};
    for (int k = 0; k < 4; k++) {
        char cam[96], doc[2048];
        snprintf(cam, sizeof cam, ",\"shutter\":[%g,%g]", shutters[k][0], shutters[k][1]);
        snprintf(doc, sizeof doc,
                 SLIDE_HEAD "\"shapes\":[" SQUARE(-4, -2.5, 0) ",\"motion\":{\"times\":[0,1],\"transform\":"
                            "[{\"translate\":[6,0,0]}]}}],\"lights\":[{\"type\":\"infinite\",\"radiance\":1}]}",
                 cam);
        ts_scene *s = load_json(doc);
        assert_true(s->effects & TS_EFFECT_MOTION);
        ts_film *f = render(s, 4096, 2);
        check_columns(f, 1, -4, 1.5, 6, shutters[k][0], shutters[k][1], "sliding square");
        ts_film_destroy(f);
        ts_scene_destroy(s);
    }
}

/* The camera slides −6 past a still square: the same image as the square sliding +6. */
static void slide_camera_motion(void **state)
{
    (void)state;
    const char *doc = SLIDE_HEAD "\"shapes\":[" SQUARE(-4, -2.5, 0) "}],"
                      "\"lights\":[{\"type\":\"infinite\",\"radiance\":1}]}";
    char d[2048];
    snprintf(d, sizeof d, doc,
             ",\"motion\":{\"times\":[0,1],\"start\":[{\"translate\":[0,0,10]}],"
             "\"end\":[{\"translate\":[-6,0,10]}]}");
    ts_scene *s = load_json(d);
    assert_true(s->camera.moving && (s->effects & TS_EFFECT_MOTION));
    ts_film *f = render(s, 4096, 2);
    check_columns(f, 1, -4, 1.5, 6, 0, 1, "moving camera");
    ts_film_destroy(f);
    ts_scene_destroy(s);
}

/* A distant light along (1, 0, −1) of irradiance π√2 on a white floor (radiance 1), and a
 * black square at z = 5 moving from x ∈ [−12, −10.5] by +6: never in the camera's view
 * (x < −4 at that height), its shadow x ∈ [−7, −5.5] + 6τ is. Only shadow rays that keep
 * the camera ray's time see it there (with time 0 the shadow stays out of view). */
static void slide_shadow_rays(void **state)
{
    (void)state;
    char doc[4096];
    snprintf(doc, sizeof doc,
             SLIDE_HEAD "\"shapes\":[" SQUARE(-12, -10.5, 5) ",\"motion\":{\"transform\":[{\"translate\":[6,0,0]}]}},"
                        "{\"type\":\"mesh\",\"positions\":[-20,-20,0,20,-20,0,20,20,0,-20,20,0],\"indices\":[0,1,2,0,2,3],"
                        "\"material\":\"white\"}],"
                        "\"lights\":[{\"type\":\"distant\",\"from\":[0,0,0],\"to\":[1,0,-1],\"irradiance\":%.17g}]}",
             "", 3.14159265358979323846 * sqrt(2.0));
    /* the white material beside the black one */
    char *m = strstr(doc, "\"black\":{");
    char fixed[4096];
    snprintf(fixed, sizeof fixed, "%.*s\"white\":{\"type\":\"diffuse\",\"reflectance\":1},%s", (int)(m - doc), doc, m);
    ts_scene *s = load_json(fixed);
    ts_film *f = render(s, 4096, 2);
    double l0 = ts_film_pixel_rgb(f, 7, 0).g; /* never shadowed: ρ/π · E · cos 45° = 1 to rounding */
    assert_true(fabs(l0 - 1) < 1e-5);
    check_columns(f, l0, -7, 1.5, 6, 0, 1, "sliding shadow");
    ts_film_destroy(f);
    ts_scene_destroy(s);
}

/* The document of square (SQUARE(…)) moving by motion (a transform list) with its shutter
 * shut at t, into a; the static instance of it at mo's matrix at t, into b. */
static void shut_docs(char *a, char *b, size_t n, const char *square, const char *motion, const ts_anim_xform *mo,
                      double t)
{
    const char *lights = LIGHTS;
    ts_mat4 m = ts_anim_xform_matrix(mo, t);
    char mat[600] = "", cam[64];
    for (int i = 0; i < 16; i++)
        snprintf(mat + strlen(mat), sizeof mat - strlen(mat), "%s%.17g", i ? "," : "", m.m[i / 4][i % 4]);
    snprintf(cam, sizeof cam, ",\"shutter\":[%.17g,%.17g]", t, t);
    snprintf(a, n, SLIDE_HEAD "\"shapes\":[%s,\"motion\":{\"transform\":%s}}],%s", cam, square, motion, lights);
    snprintf(b, n,
             SLIDE_HEAD "\"objects\":{\"o\":{\"shapes\":[%s}]}},"
                        "\"instances\":[{\"object\":\"o\",\"transform\":[{\"matrix\":[%s]}]}],%s",
             "", square, mat, lights);
}

/* What does not move renders as before, bit for bit, and costs no sample dimension:
 * a motion to the same transform; a shut shutter (at the motion's start: the keyframe; in
 * the middle: the interpolated matrix as a static instance); and the thread count does not
 * change a moving scene's pixels. */
static void static_equivalence(void **state)
{
    (void)state;
    const char *lights = LIGHTS;
    char a[2048], b[2048];
    /* Sobol here: the dimensions matter. */
    snprintf(a, sizeof a,
             SLIDE_HEAD "\"shapes\":[" SQUARE(-4, -2.5, 0) ",\"transform\":[{\"translate\":[1,0,0]}],"
                        "\"motion\":{\"times\":[0,3],\"transform\":[{\"translate\":[1,0,0]}]}}],%s",
             "", lights);
    snprintf(b, sizeof b, SLIDE_HEAD "\"shapes\":[" SQUARE(-4, -2.5, 0) ",\"transform\":[{\"translate\":[1,0,0]}]}],%s",
             "", lights);
    to_sobol(a);
    to_sobol(b);
    ts_scene *sa = load_json(a), *sb = load_json(b);
    assert_false(sa->effects & TS_EFFECT_MOTION);
    assert_int_equal(sa->n_instances, 0);
    ts_film *fa = render(sa, 64, 2), *fb = render(sb, 64, 2);
    assert_true(films_equal(fa, fb));
    ts_film_destroy(fa), ts_film_destroy(fb);
    ts_scene_destroy(sa), ts_scene_destroy(sb);

    /* Shut shutters against static instances of the transform at that time. */
    const double at[] = {0, 0.5, 1.5};
    for (int k = 0; k < 3; k++) {
        ts_xform x0 = ts_xform_identity(), r = ts_xform_rotate(150, (ts_dvec3){0.2, 0.3, 1});
        ts_xform tr = ts_xform_translate((ts_dvec3){2, 0.5, 0}), x1 = ts_xform_compose(&tr, &r);
        ts_anim_xform mo;
        assert_true(ts_anim_xform_init(&mo, &x0, 0, &x1, 1));
        shut_docs(a, b, sizeof a, SQUARE(-1, 1, 0), "[{\"rotate\":{\"angle\":150,\"axis\":[0.2,0.3,1]}},"
                  "{\"translate\":[2,0.5,0]}]", &mo, at[k]);
        sa = load_json(a), sb = load_json(b);
        assert_false(sa->effects & TS_EFFECT_MOTION);
        fa = render(sa, 256, 2), fb = render(sb, 256, 2);
        if (!films_equal(fa, fb)) fail_msg("shutter shut at %g: not the static instance's image", at[k]);
        ts_film_destroy(fa), ts_film_destroy(fb);
        ts_scene_destroy(sa), ts_scene_destroy(sb);
    }

    /* Threads 1 and 3, a moving scene: the same pixels. */
    snprintf(a, sizeof a,
             SLIDE_HEAD "\"shapes\":[" SQUARE(-1, 1, 0) ",\"motion\":{\"transform\":[{\"rotate\":{\"angle\":150,"
                        "\"axis\":[0,0,1]}},{\"scale\":[1,2,1]}]}}],%s",
             "", lights);
    sa = load_json(a);
    assert_true(sa->effects & TS_EFFECT_MOTION);
    fa = render(sa, 64, 1), fb = render(sa, 64, 3);
    assert_true(films_equal(fa, fb));
    ts_film_destroy(fa), ts_film_destroy(fb);
    ts_scene_destroy(sa);
}

/* Rotation with a non-uniform scale (shear in pbrt's S: Embree follows it by 129 steps,
 * accel.h): at shut shutters inside the motion the image is the static instance's at that
 * matrix, but for pixels whose samples Embree's stepped traversal sends the other way at a
 * silhouette — counted: at most 1% of the samples' pixel means may differ. */
static void rotating_sheared(void **state)
{
    (void)state;
    char a[2048], b[2048];
    int differ = 0, total = 0;
    for (int k = 1; k < 8; k++) {
        double t = k / 8.0;
        ts_xform x0 = ts_xform_identity(), sc = ts_xform_scale((ts_dvec3){1, 0.3, 1}),
                 r = ts_xform_rotate(120, (ts_dvec3){0, 0, 1});
        ts_xform x1 = ts_xform_compose(&sc, &r); /* rotate, then scale: S is not diagonal */
        ts_anim_xform mo;
        assert_true(ts_anim_xform_init(&mo, &x0, 0, &x1, 1));
        assert_true(mo.s[1].m[0][1] != 0);
        shut_docs(a, b, sizeof a, SQUARE(-2, 2, 0), "[{\"rotate\":{\"angle\":120,\"axis\":[0,0,1]}},"
                  "{\"scale\":[1,0.3,1]}]", &mo, t);
        ts_scene *sa = load_json(a), *sb = load_json(b);
        ts_film *fa = render(sa, 256, 2), *fb = render(sb, 256, 2);
        for (int i = 0; i < fa->width * fa->height; i++, total++)
            differ += memcmp(&fa->pixels[i], &fb->pixels[i], sizeof fa->pixels[i]) != 0;
        ts_film_destroy(fa), ts_film_destroy(fb);
        ts_scene_destroy(sa), ts_scene_destroy(sb);
    }
    fprintf(stderr, "rotating_sheared: %d of %d pixels differ from the static instance's\n", differ, total);
    assert_true(differ <= total / 100);
}

/* JSON refusals, each naming its path; the motion is part of the scene digest. */
static void json_refusals(void **state)
{
    (void)state;
    char d[2048], e[2048];
    snprintf(d, sizeof d, SLIDE_HEAD "\"shapes\":[" SQUARE(-1, 1, 0) ",\"motion\":{\"transform\":[]}}]," LIGHTS, "");
    snprintf(e, sizeof e, SLIDE_HEAD "\"shapes\":[" SQUARE(-1, 1, 0) ",\"motion\":{\"times\":[0,2],\"transform\":[]}}]," LIGHTS,
             "");
    ts_scene *sd = load_json(d), *se = load_json(e);
    assert_string_not_equal(sd->digest, se->digest);
    ts_scene_destroy(sd), ts_scene_destroy(se);
    const char *lights = LIGHTS;
    snprintf(d, sizeof d,
             SLIDE_HEAD "\"shapes\":[" SQUARE(-1, 1, 0) ",\"motion\":{\"times\":[1,1],\"transform\":[{\"translate\":[1,0,0]}]}}],%s",
             "", lights);
    expect_json_error(d, "shapes[0]: motion.times: the end time 1 must be after the start time 1");
    snprintf(d, sizeof d,
             SLIDE_HEAD "\"shapes\":[" SQUARE(-1, 1, 0) ",\"motion\":{\"times\":[2,1],\"transform\":[]}}],%s", "", lights);
    expect_json_error(d, "shapes[0].motion.times: expected [start, end], two finite numbers with start ≤ end");
    snprintf(d, sizeof d, SLIDE_HEAD "\"shapes\":[" SQUARE(-1, 1, 0) ",\"motion\":{\"times\":[0,1]}}],%s", "", lights);
    expect_json_error(d, "shapes[0].motion.transform: required (an array) but missing");
    snprintf(d, sizeof d,
             SLIDE_HEAD "\"shapes\":[" SQUARE(-1, 1, 0) ",\"emission\":1,\"motion\":{\"transform\":[{\"translate\":[1,0,0]}]}}],%s",
             "", lights);
    expect_json_error(d, "shapes[0]: emission: a moving shape cannot emit (pbrt-v3 ignores the area light of an "
                         "animated shape)");
    snprintf(d, sizeof d, SLIDE_HEAD "\"shapes\":[" SQUARE(-1, 1, 0) "}],%s", ",\"shutter\":[1,0]", lights);
    expect_json_error(d, "camera.shutter: expected [start, end], two finite numbers with start ≤ end");
    snprintf(d, sizeof d,
             SLIDE_HEAD "\"objects\":{\"o\":{\"shapes\":[" SQUARE(-1, 1, 0) ",\"motion\":{\"transform\":[]}}]}},%s", "",
             lights);
    expect_json_error(d, "objects.o.shapes[0].motion: a shape of an object cannot move (a moving shape is an instance "
                         "of its own, and instances do not nest); move the object's instances instead");
}

/* Embree's time steps are bounded (geometry/accel.h): 8129 sheared moving instances (129
 * steps each) are refused before anything is built, the sentence naming the count. (8128
 * fit, but building their motion BVH takes a minute: not checked here.) */
static void step_limit(void **state)
{
    (void)state;
    for (int n = 8129; n <= 8129; n++) {
        size_t cap = 512 + (size_t)n * 120;
        char *doc = malloc(cap);
        size_t len = (size_t)snprintf(doc, cap,
                                      "{\"tessera\":1,\"camera\":{\"from\":[0,0,5],\"to\":[0,0,0]},\"film\":{\"width\":2,"
                                      "\"height\":2},\"materials\":{\"m\":{\"type\":\"diffuse\"}},\"objects\":{\"o\":{\"shapes\":"
                                      "[{\"type\":\"sphere\",\"radius\":1,\"material\":\"m\"}]}},\"instances\":[");
        for (int k = 0; k < n; k++)
            len += (size_t)snprintf(doc + len, cap - len,
                                    "%s{\"object\":\"o\",\"motion\":{\"transform\":[{\"rotate\":{\"angle\":90,\"axis\":[0,0,1]}},"
                                    "{\"scale\":[1,2,1]}]}}",
                                    k ? "," : "");
        snprintf(doc + len, cap - len, "]}");
        ts_scene *s = NULL;
        ts_error err = {0};
        ts_status st = ts_scene_load_text(doc, strlen(doc), NULL, "t", NULL, &s, &err);
        {
            assert_int_equal(st, TS_ERR_LIMIT);
            assert_string_equal(err.message,
                                "instances: the moving shapes and instances need 1048641 time steps of the "
                                "ray-intersection structure, more than its limit of 1048576 (a motion with shear, or "
                                "over part of the scene's motion interval, takes 129, others 2)");
        }
        free(doc);
    }
}

/* pbrt-v3: ActiveTransform selects the CTMs the transform directives change; a shape
 * under differing CTMs moves, its area light is dropped with pbrt-v3's message; the
 * camera's shutter and animated CameraToWorld; convert writes the motion and renders the
 * same pixels; TransformTimes with equal transforms is the static scene bit for bit. */
#define PBRT_HEAD                                                                                                  \
    "TransformTimes 0 1\n"                                                                                         \
    "LookAt 0 0 10  0 0 0  0 1 0\nCamera \"orthographic\" \"float screenwindow\" [-4 4 -2 2]%s\n"                  \
    "Film \"image\" \"integer xresolution\" 8 \"integer yresolution\" 4\nPixelFilter \"box\"\n"                     \
    "Sampler \"random\" \"integer pixelsamples\" 64\nIntegrator \"path\" \"integer maxdepth\" 1\n"                 \
    "WorldBegin\nLightSource \"infinite\" \"rgb L\" [1 1 1]\n"
#define PBRT_SQUARE                                                                                                \
    "Material \"matte\" \"rgb Kd\" [0 0 0]\n"                                                                      \
    "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [-4 -3 0 -2.5 -3 0 -2.5 3 0 -4 3 0]\n"

static void pbrt_motion(void **state)
{
    (void)state;
    char text[2048];
    warnings w = {0};
    /* Moving square: AttributeBegin saves the active transform; EndTime moves the end CTM only. */
    snprintf(text, sizeof text,
             PBRT_HEAD "AttributeBegin\nActiveTransform EndTime\nTranslate 6 0 0\nActiveTransform All\n"
                       "AreaLightSource \"diffuse\" \"rgb L\" [1 1 1]\n" PBRT_SQUARE "AttributeEnd\nWorldEnd\n",
             "");
    ts_scene *s = load_pbrt(text, &w);
    assert_true(s->effects & TS_EFFECT_MOTION);
    assert_int_equal(s->n_instances, 1);
    assert_non_null(s->instances[0].motion);
    assert_int_equal(s->n_lights, 1); /* the area light was dropped */
    assert_non_null(strstr(w.all, "t.pbrt:16:1: Shape \"trianglemesh\" is animated: its area light is ignored (as "
                                  "pbrt-v3 does: \"Ignoring currently set area light when creating animated shape\")"));
    ts_scene_destroy(s);

    /* Convert writes the motion; the document renders what the .pbrt renders. */
    char path[4096];
    ts_tmp_write("motion.pbrt", text, strlen(text), path, sizeof path);
    char *json = NULL;
    size_t len;
    ts_error err = {0};
    assert_int_equal(ts_scene_convert_pbrt_path(path, NULL, NULL, NULL, &json, &len, &err), TS_OK);
    assert_non_null(strstr(json, "\"motion\""));
    ts_scene *sj = load_json(json), *sp = load_pbrt(text, &w);
    ts_film *fj = render(sj, 64, 2), *fp = render(sp, 64, 2);
    assert_true(films_equal(fj, fp));
    ts_film_destroy(fj), ts_film_destroy(fp);
    ts_scene_destroy(sj), ts_scene_destroy(sp);
    free(json);

    /* The camera: shutter and an animated CameraToWorld, written out by convert too. */
    snprintf(text, sizeof text,
             "TransformTimes 0 1\nActiveTransform EndTime\nTranslate 6 0 0\nActiveTransform All\n"
             "LookAt 0 0 10  0 0 0  0 1 0\nCamera \"orthographic\" \"float screenwindow\" [-4 4 -2 2] "
             "\"float shutteropen\" 0.25 \"float shutterclose\" 0.75\n"
             "Film \"image\" \"integer xresolution\" 8 \"integer yresolution\" 4\nPixelFilter \"box\"\n"
             "Sampler \"random\" \"integer pixelsamples\" 64\nIntegrator \"path\" \"integer maxdepth\" 1\n"
             "WorldBegin\nLightSource \"infinite\" \"rgb L\" [1 1 1]\n" PBRT_SQUARE "WorldEnd\n");
    s = load_pbrt(text, &w);
    assert_true(s->camera.moving && s->camera.shutter_open == 0.25f && s->camera.shutter_close == 0.75f);
    ts_scene_destroy(s);
    ts_tmp_write("camera.pbrt", text, strlen(text), path, sizeof path);
    assert_int_equal(ts_scene_convert_pbrt_path(path, NULL, NULL, NULL, &json, &len, &err), TS_OK);
    assert_non_null(strstr(json, "\"shutter\""));
    sj = load_json(json), sp = load_pbrt(text, &w);
    fj = render(sj, 64, 2), fp = render(sp, 64, 2);
    assert_true(films_equal(fj, fp));
    ts_film_destroy(fj), ts_film_destroy(fp);
    ts_scene_destroy(sj), ts_scene_destroy(sp);
    free(json);

    /* TransformTimes and ActiveTransform that end with equal CTMs: the static scene. */
    char a[2048], b[2048];
    snprintf(a, sizeof a,
             PBRT_HEAD "ActiveTransform StartTime\nTranslate 1 0 0\nActiveTransform EndTime\nTranslate 1 0 0\n"
                       "ActiveTransform All\n" PBRT_SQUARE "WorldEnd\n",
             "");
    snprintf(b, sizeof b, PBRT_HEAD "Translate 1 0 0\n" PBRT_SQUARE "WorldEnd\n", "");
    ts_scene *sa = load_pbrt(a, &w), *sb = load_pbrt(b, &w);
    assert_false(sa->effects & TS_EFFECT_MOTION);
    ts_film *fa = render(sa, 64, 2), *fb = render(sb, 64, 2);
    assert_true(films_equal(fa, fb));
    ts_film_destroy(fa), ts_film_destroy(fb);
    ts_scene_destroy(sa), ts_scene_destroy(sb);

    /* An animated ObjectInstance moves the object. */
    snprintf(a, sizeof a,
             PBRT_HEAD "ObjectBegin \"sq\"\n" PBRT_SQUARE "ObjectEnd\nActiveTransform EndTime\nTranslate 6 0 0\n"
                       "ActiveTransform All\nObjectInstance \"sq\"\nWorldEnd\n",
             "");
    sa = load_pbrt(a, &w);
    assert_true((sa->effects & TS_EFFECT_MOTION) && sa->n_instances == 1 && sa->instances[0].motion);
    ts_scene_destroy(sa);
}

static void pbrt_refusals(void **state)
{
    (void)state;
    expect_pbrt_error("TransformTimes 1 0\nWorldBegin\nWorldEnd\n",
                      "t.pbrt:1:1: TransformTimes: the end time 0 is before the start time 1");
    expect_pbrt_error("ActiveTransform Later\nWorldBegin\nWorldEnd\n",
                      "t.pbrt:1:17: ActiveTransform expects All, StartTime or EndTime, got Later");
    expect_pbrt_error("WorldBegin\nTransformTimes 0 1\nWorldEnd\n",
                      "t.pbrt:2:1: TransformTimes is an option and must come before WorldBegin");
    char text[2048];
    snprintf(text, sizeof text,
             "TransformTimes 2 2\nWorldBegin\nActiveTransform EndTime\nTranslate 1 0 0\nActiveTransform All\n"
             "Shape \"sphere\"\nWorldEnd\n");
    expect_pbrt_error(text, "t.pbrt:6:1: Shape \"sphere\": the transformation is animated (ActiveTransform) but "
                            "TransformTimes gives no interval (start and end time 2)");
    snprintf(text, sizeof text,
             "ActiveTransform EndTime\nScale 1 0 1\nActiveTransform All\nCamera \"perspective\"\nWorldBegin\nWorldEnd\n");
    expect_pbrt_error(text, "t.pbrt:4:1: Camera: the current transformation at the end time (ActiveTransform EndTime) is singular");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(slide_camera_rays),  cmocka_unit_test(slide_camera_motion),
        cmocka_unit_test(slide_shadow_rays),  cmocka_unit_test(static_equivalence),
        cmocka_unit_test(rotating_sheared),   cmocka_unit_test(json_refusals),
        cmocka_unit_test(pbrt_motion),        cmocka_unit_test(pbrt_refusals),
        cmocka_unit_test(step_limit),
    };
    return cmocka_run_group_tests(tests, ts_tmp_group_setup, ts_tmp_group_teardown);
}
