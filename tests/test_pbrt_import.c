/* test_pbrt_import.c — the pbrt-v3 front end's mapping (renderer/pbrt3/pbrt_import.h,
 * scene_load.h, spectrum.h): small pbrt-v3 scenes written inline, each mapping checked
 * against pbrt-v3's definitions in closed form — camera rays against pbrt-v3's
 * raster → screen → camera chain, filters against their formulas, spectra against the
 * CIE's normalisation — or against the JSON v1 document it is equivalent to; and the
 * error sentences, exactly. */
// clang-format off
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>
// clang-format on

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cjson/cJSON.h>

#include "geometry/accel.h"
#include "geometry/interaction.h"
#include "image/exr.h"
#include "render/render.h"
#include "json/scene_json.h"
#include "load/scene_load.h"
#include "media/medium.h"
#include "spectrum/spectrum.h"
#include "render_stats.h"
#include "tmp_folder.h"

static void write_file(const char *rel, const char *text, char *path, size_t len)
{
    ts_tmp_write(rel, text, strlen(text), path, len);
}

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

static ts_scene *load(const char *text, warnings *w)
{
    ts_scene *s = NULL;
    ts_error err = {0};
    ts_status st = ts_scene_load_pbrt_text(text, strlen(text), NULL, "t.pbrt", NULL, on_warning, w, &s, &err);
    if (st) fprintf(stderr, "load failed: %s\n", err.message);
    assert_int_equal(st, TS_OK);
    return s;
}

static void expect_error(const char *text, const char *sentence)
{
    ts_scene *s = NULL;
    ts_error err = {0};
    warnings w = {0};
    ts_status st =
        ts_scene_load_pbrt_text(text, strlen(text), NULL, "t.pbrt", NULL, on_warning, &w, &s, &err);
    assert_int_not_equal(st, TS_OK);
    assert_null(s);
    if (strcmp(err.message, sentence) != 0)
        fprintf(stderr, "got:      %s\nexpected: %s\n", err.message, sentence);
    assert_string_equal(err.message, sentence);
}

/* The direction of the camera ray through raster point (x, y), lens at its centre. */
static ts_vec3 ray_dir(const ts_scene *s, float x, float y)
{
    return ts_camera_ray(&s->camera, (ts_vec2){x, y}, (ts_vec2){0.5f, 0.5f}).d;
}

static void assert_vec_near(ts_vec3 a, double x, double y, double z, double tol)
{
    if (fabs(a.x - x) > tol || fabs(a.y - y) > tol || fabs(a.z - z) > tol)
        fprintf(stderr, "got (%.7f %.7f %.7f), expected (%.7f %.7f %.7f)\n", a.x, a.y, a.z, x, y, z);
    assert_true(fabs(a.x - x) <= tol && fabs(a.y - y) <= tol && fabs(a.z - z) <= tol);
}

#define WORLD "WorldBegin\nLightSource \"point\" \"point from\" [0 0 -1]\nShape \"sphere\"\nWorldEnd\n"

/* pbrt-v3: raster (0, 0) is screen (pMin.x, pMax.y); the screen window of a 2:1 film is
 * [-2, 2] × [-1, 1] in units of tan(fov/2); camera +x is image right, +y up, +z forward,
 * and LookAt's camera-to-world columns are (normalize(up × dir), dir × right, dir). */
static void camera_lookat_orientation(void **state)
{
    (void)state;
    warnings w = {0};
    ts_scene *s = load("LookAt 0 0 0  0 0 1  0 1 0\nCamera \"perspective\" \"float fov\" 90\n"
                       "Film \"image\" \"integer xresolution\" 64 \"integer yresolution\" 32\n" WORLD,
                       &w);
    double k = 1 / sqrt(6.0);
    assert_vec_near(ray_dir(s, 0, 0), -2 * k, k, k, 2e-6);   /* top left: −x, +y */
    assert_vec_near(ray_dir(s, 64, 32), 2 * k, -k, k, 2e-6); /* bottom right */
    assert_vec_near(ray_dir(s, 32, 16), 0, 0, 1, 2e-6);
    ts_scene_destroy(s);

    /* A mirroring transform before LookAt (as exporters write) turns the image around x. */
    s = load("Scale -1 1 1\nLookAt 0 0 0  0 0 1  0 1 0\nCamera \"perspective\" \"float fov\" 90\n"
             "Film \"image\" \"integer xresolution\" 64 \"integer yresolution\" 32\n" WORLD,
             &w);
    assert_vec_near(ray_dir(s, 0, 0), 2 * k, k, k, 2e-6);
    ts_scene_destroy(s);
}

/* screenwindow and frameaspectratio replace the window; fov is along the shorter axis. */
static void camera_screen_window(void **state)
{
    (void)state;
    warnings w = {0};
    ts_scene *s = load("Camera \"perspective\" \"float fov\" 90 \"float screenwindow\" [-1 1 -1 1]\n"
                       "Film \"image\" \"integer xresolution\" 64 \"integer yresolution\" 32\n" WORLD,
                       &w);
    double k = 1 / sqrt(3.0);
    assert_vec_near(ray_dir(s, 0, 0), -k, k, k, 2e-6);
    ts_scene_destroy(s);
    /* A portrait film: x spans [-1, 1], y [-2, 2] (fov along x). */
    s = load("Camera \"perspective\" \"float fov\" 90\n"
             "Film \"image\" \"integer xresolution\" 32 \"integer yresolution\" 64\n" WORLD,
             &w);
    double q = 1 / sqrt(6.0);
    assert_vec_near(ray_dir(s, 0, 0), -q, 2 * q, q, 2e-6);
    ts_scene_destroy(s);
    /* An uneven window is off-centre. */
    s = load("Camera \"perspective\" \"float fov\" 90 \"float screenwindow\" [0 1 0 1]\n"
             "Film \"image\" \"integer xresolution\" 32 \"integer yresolution\" 32\n" WORLD,
             &w);
    assert_vec_near(ray_dir(s, 16, 16), 0.5 / sqrt(1.5), 0.5 / sqrt(1.5), 1 / sqrt(1.5),
                    2e-6); /* screen (0.5, 0.5) */
    ts_scene_destroy(s);
}

/* Orthographic: the window [-2, 2] × [-1, 1] in camera-space units, rays along +z. */
static void camera_orthographic(void **state)
{
    (void)state;
    warnings w = {0};
    ts_scene *s = load("LookAt 0 0 -5  0 0 0  0 1 0\nCamera \"orthographic\"\n"
                       "Film \"image\" \"integer xresolution\" 64 \"integer yresolution\" 32\n" WORLD,
                       &w);
    ts_ray r = ts_camera_ray(&s->camera, (ts_vec2){0, 0}, (ts_vec2){0.5f, 0.5f});
    assert_vec_near(r.o, -2, 1, -5, 2e-6);
    assert_vec_near(r.d, 0, 0, 1, 2e-6);
    ts_scene_destroy(s);
}

/* Film "scale" and "maxsampleluminance" (pbrt-v3's ImageFilm): on the scene, into the
 * converted document, refused where pbrt-v3's image would be meaningless; defaults 1 and
 * no clamp. */
static void film_scale_and_clamp(void **state)
{
    (void)state;
    warnings w = {0};
    ts_scene *s = load("Film \"image\" \"integer xresolution\" 8 \"integer yresolution\" 8\n" WORLD, &w);
    assert_true(s->film_scale == 1 && s->max_sample_luminance == INFINITY);
    ts_scene_destroy(s);
    static const char text[] = "Film \"image\" \"integer xresolution\" 8 \"integer yresolution\" 8 "
                               "\"float scale\" [1.5] \"float maxsampleluminance\" [10]\n" WORLD;
    w.n = 0;
    s = load(text, &w);
    assert_true(s->film_scale == 1.5f && s->max_sample_luminance == 10);
    assert_int_equal(w.n, 0); /* both are used: no "is not used" warning */
    ts_scene_destroy(s);
    char *json = NULL, path[4096];
    size_t len = 0;
    ts_error err = {0};
    write_file("film.pbrt", text, path, sizeof path);
    assert_int_equal(ts_scene_convert_pbrt_path(path, NULL, NULL, NULL, &json, &len, &err), TS_OK);
    cJSON *doc = cJSON_Parse(json), *film = cJSON_GetObjectItem(doc, "film");
    assert_true(cJSON_GetObjectItem(film, "scale")->valuedouble == 1.5);
    assert_true(cJSON_GetObjectItem(film, "max_sample_luminance")->valuedouble == 10);
    cJSON_Delete(doc);
    free(json);
    expect_error("Film \"image\" \"float scale\" [0]\n" WORLD,
                 "t.pbrt:1:14: Film \"image\": \"float scale\" must be a finite number > 0, got 0");
    expect_error("Film \"image\" \"float maxsampleluminance\" [-1]\n" WORLD,
                 "t.pbrt:1:14: Film \"image\": \"float maxsampleluminance\" must be a number > 0, got -1");
}

/* A dots texture is made as pbrt-v3 renders it (test_texture's test_pbrt_dots_swapped),
 * and the load says so at the Texture directive. */
static void dots_swap_warned(void **state)
{
    (void)state;
    warnings w = {0};
    ts_scene *s = load("WorldBegin\nTexture \"d\" \"color\" \"dots\" \"rgb inside\" [1 0 0]\n"
                       "Material \"matte\" \"texture Kd\" \"d\"\nShape \"sphere\"\nWorldEnd\n",
                       &w);
    assert_int_equal(w.n, 1);
    assert_string_equal(w.last, "t.pbrt:2:1: Texture \"d\": paints its dots with \"outside\" and the rest with "
                                "\"inside\", as pbrt-v3 renders it (pbrt-v3's textures/dots.cpp passes the two "
                                "swapped); its JSON conversion names them by what they paint");
    /* pbrt-v3 clamps textured colours at 0 only (docs/design.md's clamping Decision). */
    assert_true(s->materials[s->shapes[0].material].texture_clamp_nonneg);
    ts_scene_destroy(s);
    /* marble keeps the book's spline (docs/design.md's Decision) and says so. */
    w.n = 0;
    s = load("WorldBegin\nTexture \"mb\" \"color\" \"marble\"\n"
             "Material \"matte\" \"texture Kd\" \"mb\"\nShape \"sphere\"\nWorldEnd\n",
             &w);
    assert_int_equal(w.n, 1);
    assert_non_null(strstr(w.last, "t.pbrt:2:1: Texture \"mb\": renders as the book's marble, not pbrt-v3's"));
    assert_non_null(strstr(w.last, "the image differs from pbrt-v3's"));
    ts_scene_destroy(s);
}

/* A shutter whose open is after its close is swapped with a warning, pbrt-v3's message:
 * also when only shutteropen is given (after shutterclose's default 1), the case the
 * pbrt_import fuzzer found reading a null parameter. */
static void shutter_swapped_warned(void **state)
{
    (void)state;
    static const char *const cams[] = {"\"float shutteropen\" 5 \"float shutterclose\" 0.5",
                                       "\"float shutteropen\" 5"};
    static const char *const want[] = {"\"float shutterclose\" 0.5 is before shutteropen 5",
                                       "\"float shutteropen\" 5 is after shutterclose's default 1"};
    for (int k = 0; k < 2; k++) {
        char doc[512];
        snprintf(doc, sizeof doc, "Camera \"perspective\" %s\nWorldBegin\nShape \"sphere\"\nWorldEnd\n", cams[k]);
        warnings w = {0};
        ts_scene *s = load(doc, &w);
        assert_int_equal(w.n, 1);
        if (!strstr(w.last, want[k])) fail_msg("warning \"%s\" lacks \"%s\"", w.last, want[k]);
        ts_scene_destroy(s);
    }
}

/* NamedMaterial of a material not (yet) defined: pbrt-v3 reports an error and keeps the
 * material in force; so does the import, with a warning at the directive. */
static void named_material_unknown_kept(void **state)
{
    (void)state;
    warnings w = {0};
    ts_scene *s = load("WorldBegin\nMaterial \"mirror\"\nNamedMaterial \"later\"\nShape \"sphere\"\n"
                       "MakeNamedMaterial \"later\" \"string type\" \"matte\"\nWorldEnd\n",
                       &w);
    assert_int_equal(w.n, 1);
    assert_string_equal(w.last, "t.pbrt:3:1: NamedMaterial \"later\": no material of that name is defined here; the "
                                "material in force stays (pbrt-v3 reports an error and goes on the same way)");
    assert_int_equal(s->n_shapes, 1);
    assert_int_equal(s->materials[s->shapes[0].material].type, TS_MATERIAL_MIRROR);
    ts_scene_destroy(s);
}

/* pbrt-v3's gaussian: f(x) = exp(−α x²) − exp(−α r²), α = 2, r = 2 by default. */
static void filter_gaussian(void **state)
{
    (void)state;
    warnings w = {0};
    ts_scene *s = load("PixelFilter \"gaussian\"\nFilm \"image\" \"integer xresolution\" 8 \"integer "
                       "yresolution\" 8\n" WORLD,
                       &w);
    assert_int_equal(s->filter.type, TS_FILTER_GAUSSIAN);
    assert_float_equal(s->filter.radius, 2, 0);
    double floor_v = exp(-8.0), integral = sqrt(TS_PI_D / 2) * erf(2 * sqrt(2.0)) - 4 * floor_v;
    double f1_0 = (1 - floor_v) / integral, f1_1 = (exp(-2.0) - floor_v) / integral;
    assert_float_equal(ts_filter_eval(&s->filter, (ts_vec2){0, 0}), f1_0 * f1_0, 1e-5 * f1_0 * f1_0);
    assert_float_equal(ts_filter_eval(&s->filter, (ts_vec2){1, 0}), f1_1 * f1_0, 1e-5 * f1_0 * f1_0);
    ts_scene_destroy(s);
    s = load("PixelFilter \"gaussian\" \"float alpha\" 0.5 \"float xwidth\" 3 \"float ywidth\" 3\n" WORLD,
             &w);
    floor_v = exp(-4.5);
    integral = sqrt(TS_PI_D / 0.5) * erf(3 * sqrt(0.5)) - 6 * floor_v;
    f1_0 = (1 - floor_v) / integral;
    assert_float_equal(s->filter.radius, 3, 0);
    assert_float_equal(ts_filter_eval(&s->filter, (ts_vec2){0, 0}), f1_0 * f1_0, 1e-5 * f1_0 * f1_0);
    ts_scene_destroy(s);
}

/* An equal-energy spectrum has x = y = z by the CIE's normalisation (∫x̄ = ∫ȳ = ∫z̄), so it
 * is the XYZ → sRGB matrix's row sums times pbrt-v3's Y of it, (830 − 360)/471 ∫ȳ/∫ȳ. */
static void spectrum_equal_energy(void **state)
{
    (void)state;
    float flat[4] = {300, 1, 900, 1};
    ts_rgb c = ts_spectrum_to_rgb(flat, 2);
    double y = 470.0 / 471.0;
    /* The 1 nm sums of x̄, z̄ differ from ȳ's by under 0.1 %. */
    assert_float_equal(c.r, 1.204794 * y, 2e-3);
    assert_float_equal(c.g, 0.948291 * y, 2e-3);
    assert_float_equal(c.b, 0.908916 * y, 2e-3);
    /* Unsorted pairs are sorted first. */
    float a[6] = {400, 0.2f, 500, 0.5f, 600, 0.9f}, b[6] = {600, 0.9f, 400, 0.2f, 500, 0.5f};
    ts_rgb ca = ts_spectrum_to_rgb(a, 3), cb = ts_spectrum_to_rgb(b, 3);
    assert_true(ca.r == cb.r && ca.g == cb.g && ca.b == cb.b);
}

static void error_sentences(void **state)
{
    (void)state;
    expect_error("WorldBegin\nShape \"sphere\" \"float radius\" [1 2]\nWorldEnd\n",
                 "t.pbrt:2:16: Shape \"sphere\": \"float radius\" expects 1 value, got 2");
    expect_error("WorldBegin\nShape \"hyperboloid\"\nWorldEnd\n",
                 "t.pbrt:2:1: Shape \"hyperboloid\" is not supported (sphere, disk, cylinder, trianglemesh, "
                 "plymesh, loopsubdiv and curve are)");
    expect_error("Camera \"environment\"\nWorldBegin\nWorldEnd\n",
                 "t.pbrt:1:1: Camera \"environment\" is not supported (perspective and orthographic are)");
    expect_error("WorldBegin\nMaterial \"disney\"\nShape \"sphere\"\nWorldEnd\n",
                 "t.pbrt:2:1: Material \"disney\" is not supported (the Disney BSDF is not implemented)");
    expect_error(
        "WorldBegin\nShape \"trianglemesh\" \"point P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 3]\n"
        "WorldEnd\n",
        "t.pbrt:2:52: Shape \"trianglemesh\": \"integer indices\" value 2 is 3, not a vertex index in [0, "
        "2]");
}

/* Lights: positions through the light's CTM, colours times scale, pbrt-v3's defaults. */
static void lights_mapped(void **state)
{
    (void)state;
    warnings w = {0};
    ts_scene *s =
        load("WorldBegin\n"
             "AttributeBegin Translate 1 2 3\n"
             "LightSource \"point\" \"rgb I\" [1 2 3] \"rgb scale\" [2 2 2] \"point from\" [0 0 1]\n"
             "AttributeEnd\n"
             "LightSource \"spot\" \"point from\" [0 0 0] \"point to\" [0 0 -2] \"float coneangle\" 40\n"
             "LightSource \"distant\" \"point from\" [0 10 0] \"point to\" [0 0 0] \"rgb L\" [3 3 3]\n"
             "Shape \"sphere\"\nWorldEnd\n",
             &w);
    assert_int_equal(s->n_lights, 3);
    const ts_light *pt = &s->lights[0], *sp = &s->lights[1], *di = &s->lights[2];
    assert_int_equal(pt->type, TS_LIGHT_POINT);
    assert_vec_near(pt->position, 1, 2, 4, 0);
    assert_true(pt->color.r == 2 && pt->color.g == 4 && pt->color.b == 6);
    assert_int_equal(sp->type, TS_LIGHT_SPOT);
    assert_vec_near(sp->direction, 0, 0, -1, 1e-7);
    assert_float_equal(sp->cos_total, cos(40 * TS_PI_D / 180), 1e-6);
    assert_float_equal(sp->cos_falloff_start, cos(35 * TS_PI_D / 180), 1e-6); /* conedelta 5 */
    assert_true(sp->color.r == 1);                                            /* I defaults to 1 */
    assert_int_equal(di->type, TS_LIGHT_DISTANT);
    assert_vec_near(di->direction, 0, -1, 0, 1e-7);
    assert_true(di->color.g == 3);
    ts_scene_destroy(s);
}

/* Shapes: a sphere's radius and placement, a disk at its height, a cylinder from zmin to
 * zmax, a mesh's vertices through the CTM. */
static void shapes_mapped(void **state)
{
    (void)state;
    warnings w = {0};
    ts_scene *s = load("WorldBegin\n"
                       "AttributeBegin Translate 1 0 0 Shape \"sphere\" \"float radius\" 2 AttributeEnd\n"
                       "Shape \"disk\" \"float height\" 0.5 \"float radius\" 3 \"float innerradius\" 1\n"
                       "Shape \"cylinder\" \"float radius\" 0.5 \"float zmin\" -2 \"float zmax\" 1\n"
                       "AttributeBegin Scale 2 2 2\n"
                       "Shape \"trianglemesh\" \"point P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 2]\n"
                       "AttributeEnd\nWorldEnd\n",
                       &w);
    assert_int_equal(s->n_shapes, 4);
    const ts_shape *sp = &s->shapes[0], *dk = &s->shapes[1], *cy = &s->shapes[2], *me = &s->shapes[3];
    assert_int_equal(sp->type, TS_SHAPE_SPHERE);
    assert_float_equal(sp->sphere.radius, 2, 0);
    assert_float_equal(sp->to_world.m.m[0][3], 1, 0);
    assert_int_equal(dk->type, TS_SHAPE_DISK);
    assert_float_equal(dk->disk.radius, 3, 0);
    assert_float_equal(dk->disk.inner_radius, 1, 0);
    assert_float_equal(dk->to_world.m.m[2][3], 0.5, 0);
    assert_int_equal(cy->type, TS_SHAPE_CYLINDER);
    assert_float_equal(cy->cylinder.height, 3, 0);
    assert_float_equal(cy->to_world.m.m[2][3], -2, 0);
    assert_int_equal(me->type, TS_SHAPE_MESH);
    assert_float_equal(me->mesh.p[3], 2, 0); /* vertex 1's x, in world space */
    /* The default material is pbrt-v3's matte, Kd 0.5. */
    assert_int_equal(s->materials[sp->material].type, TS_MATERIAL_DIFFUSE);
    assert_float_equal(s->materials[sp->material].reflectance.value.g, 0.5f, 0);
    ts_scene_destroy(s);
}

/* Facing: a triangle faces along (p1 − p0) × (p2 − p0); ReverseOrientation flips it; with
 * normals pbrt-v3 turns the geometric normal toward them. An emitter shows it. */
static void mesh_orientation(void **state)
{
    (void)state;
    static const char *const cases[] = {
        /* winding faces +z (toward the camera at z = 1 looking down −z) */
        "Shape \"trianglemesh\" \"point P\" [-9 -9 0 9 -9 0 0 9 0] \"integer indices\" [0 1 2]\n",
        "ReverseOrientation\n"
        "Shape \"trianglemesh\" \"point P\" [-9 -9 0 9 -9 0 0 9 0] \"integer indices\" [0 1 2]\n",
        /* winding faces −z, the normals +z: the normals win */
        "Shape \"trianglemesh\" \"point P\" [-9 -9 0 0 9 0 9 -9 0] \"integer indices\" [0 1 2]"
        " \"normal N\" [0 0 1 0 0 1 0 0 1]\n",
        /* a disk faces +z; ReverseOrientation turns it away */
        "Shape \"disk\" \"float radius\" 9\n",
        "ReverseOrientation Shape \"disk\" \"float radius\" 9\n",
        /* loopsubdiv: pbrt-v3's limit normals point to the back of the control winding and
         * its triangles face them (mesh_subdiv.h), so an octahedron wound outwards faces in */
        "Translate 0 0 -2.5 Scale 2 2 2 Shape \"loopsubdiv\" \"integer nlevels\" 1 \"point P\" [1 0 0 -1 0 0 "
        "0 1 0 0 -1 0 0 0 1 0 0 -1]"
        " \"integer indices\" [0 2 4 1 4 2 0 4 3 1 3 4 0 5 2 1 2 5 0 3 5 1 5 3]\n",
        "Translate 0 0 -2.5 Scale 2 2 2 Shape \"loopsubdiv\" \"integer nlevels\" 1 \"point P\" [1 0 0 -1 0 0 "
        "0 1 0 0 -1 0 0 0 1 0 0 -1]"
        " \"integer indices\" [0 4 2 1 2 4 0 3 4 1 4 3 0 2 5 1 5 2 0 5 3 1 3 5]\n",
    };
    const bool lit[] = {true, false, true, true, false, false, true};
    for (int i = 0; i < 7; i++) {
        char text[1024];
        snprintf(text, sizeof text,
                 "LookAt 0 0 1  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 30\n"
                 "Film \"image\" \"integer xresolution\" 4 \"integer yresolution\" 4\n"
                 "Integrator \"path\" \"integer maxdepth\" 0\nWorldBegin\n"
                 "AreaLightSource \"diffuse\" \"rgb L\" [1 1 1]\n%sWorldEnd\n",
                 cases[i]);
        warnings w = {0};
        ts_scene *s = load(text, &w);
        ts_error err = {0};
        ts_film *f = ts_film_create(4, 4, 0, 0, 4, 4, &err);
        ts_render_stats st = {0};
        ts_render_request req = {s, s->integrator.type, f, 0, 4, 1, NULL, NULL, NULL};
        assert_int_equal(ts_render(&req, &st, &err), TS_OK);
        float v = ts_film_pixel_rgb(f, 2, 2).g;
        if ((v == 1) != lit[i]) fprintf(stderr, "case %d: centre pixel %g\n", i, v);
        assert_true(lit[i] ? v == 1 : v == 0);
        ts_film_destroy(f);
        ts_scene_destroy(s);
    }
}

static void assert_same_pixels(const ts_scene *a, const ts_scene *b, uint32_t spp);

/* PLY normals keep their lengths, as pbrt-v3's plymesh (its CreatePLYMesh hands them to
 * CreateTriangleMesh as read; Triangle::Intersect interpolates them and normalises the sum):
 * a plymesh with non-unit normals renders bit for bit as the same trianglemesh written
 * inline, which the builder already keeps (docs/design.md §4, shapes), with the CTM at
 * identity and through a rotation and a non-uniform scale; and the shading normal at a hit
 * of known barycentrics (0.5, 0.25, 0.25) is the one derived by hand. */
static void plymesh_normals_keep_lengths(void **state)
{
    (void)state;
    /* n0 = (1, 0, 1) (length √2), n1 = (0, 0, 4), n2 = (0, 2, 2) (√8). */
    static const char ply[] = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                              "property float z\nproperty float nx\nproperty float ny\nproperty float nz\n"
                              "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
                              "-1 -1 0 1 0 1\n1 -1 0 0 0 4\n0 1 0 0 2 2\n3 0 1 2\n";
    ts_tmp_write("lengths.ply", ply, strlen(ply), NULL, 0);
    static const char *const shapes[2] = {
        "Shape \"trianglemesh\" \"point P\" [-1 -1 0 1 -1 0 0 1 0] \"integer indices\" [0 1 2]"
        " \"normal N\" [1 0 1 0 0 4 0 2 2]\n",
        "Shape \"plymesh\" \"string filename\" \"lengths.ply\"\n",
    };
    static const char *const ctm[2] = {"", "Rotate 35 1 1 0 Scale 1 2 0.5\n"};
    for (int c = 0; c < 2; c++) {
        ts_scene *s[2];
        for (int k = 0; k < 2; k++) {
            char text[1024];
            snprintf(text, sizeof text,
                     "LookAt 0 0 3  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 60\n"
                     "Film \"image\" \"integer xresolution\" 16 \"integer yresolution\" 16\n"
                     "Integrator \"path\" \"integer maxdepth\" 1\nWorldBegin\n"
                     "LightSource \"point\" \"point from\" [0.5 0.5 2] \"rgb I\" [4 4 4]\n%s%sWorldEnd\n",
                     ctm[c], shapes[k]);
            warnings w = {0};
            ts_scene *sc = NULL;
            ts_error err = {0};
            if (ts_scene_load_pbrt_text(text, strlen(text), ts_tmp_dir, "t.pbrt", NULL, on_warning, &w, &sc, &err))
                fail_msg("%s", err.message);
            assert_int_equal(w.n, 0);
            s[k] = sc;
        }
        if (c == 0) {
            /* The hit at barycentrics (0.5, 0.25, 0.25): p = (−0.25, −0.5, 0). Interpolated
             * with their lengths the normals sum to (0.5, 0.5, 2), whose direction is
             * (1, 1, 4)/√18; normalised first they would give (0.354, 0.177, 0.780)/0.874. */
            const double want[3] = {1 / sqrt(18.0), 1 / sqrt(18.0), 4 / sqrt(18.0)};
            for (int k = 0; k < 2; k++) {
                ts_interaction si;
                ts_ray r = {{-0.25f, -0.5f, 5}, {0, 0, -1}, INFINITY, TS_NONE, 0, 0};
                assert_true(ts_accel_intersect(s[k]->accel, &r, &si));
                const float ns[3] = {si.ns.x, si.ns.y, si.ns.z};
                for (int a = 0; a < 3; a++)
                    if (!(fabs(ns[a] - want[a]) <= 2e-7)) /* the double result rounded to float: ≤ ½ ulp (6e-8) */
                        fail_msg("%s: ns[%d] = %.9g, by hand %.9g", k ? "plymesh" : "trianglemesh", a, ns[a], want[a]);
            }
        }
        assert_same_pixels(s[0], s[1], 4);
        ts_scene_destroy(s[0]);
        ts_scene_destroy(s[1]);
    }
}

/* directlighting's strategy "one" selects its light uniformly, as pbrt-v3's
 * DirectLightingIntegrator (UniformSampleOneLight without a light distribution): the
 * built scene's selection pmf is ½ for two lights whose powers are 1 : 9 (JSON's default,
 * power, gives 0.1 and 0.9); `convert` writes "light_sampling": "uniform", and its
 * document renders bit for bit as the .pbrt; and the image mean of 16 independent renders
 * matches the closed form. The scene: a matte plane (Kd 0.5) under two point lights, seen
 * by an orthographic camera filling the film with [−1, 1]² of the plane, box filter, so the
 * image mean is the plane's mean radiance there, (1/4)∬ (Kd/π) Σ I_k h_k / r_k³ dx dy
 * (integrated below by the midpoint rule on 1024² cells: error below 1e-7 relative, far
 * under the renders' standard error). Student's t with 15 degrees of freedom at α = 1e-3
 * two-sided (|t| < 4.07) fails correct code once in 1000 runs if the image means are
 * normal (each averages 16 × 16 pixels × 16 samples). */
static void directlighting_one_uniform(void **state)
{
    (void)state;
    static const char text[] =
        "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"orthographic\"\n"
        "Film \"image\" \"integer xresolution\" 16 \"integer yresolution\" 16\nPixelFilter \"box\"\n"
        "Sampler \"sobol\" \"integer pixelsamples\" 16\n"
        "Integrator \"directlighting\" \"string strategy\" \"one\"\nWorldBegin\n"
        "LightSource \"point\" \"point from\" [0.3 0.2 1] \"rgb I\" [1 1 1]\n"
        "LightSource \"point\" \"point from\" [-0.5 -0.4 2] \"rgb I\" [9 9 9]\n"
        "Material \"matte\" \"rgb Kd\" [0.5 0.5 0.5]\n"
        "Shape \"trianglemesh\" \"point P\" [-2 -2 0 2 -2 0 2 2 0 -2 2 0] \"integer indices\" [0 1 2 0 2 3]\n"
        "WorldEnd\n";
    char path[512];
    write_file("one.pbrt", text, path, sizeof path);
    warnings w = {0};
    ts_scene *s = load(text, &w);
    assert_int_equal(s->integrator.type, TS_INTEGRATOR_DIRECT);
    assert_int_equal(s->integrator.strategy, TS_LIGHTS_ONE);
    assert_int_equal(s->n_lights, 2);
    for (uint32_t i = 0; i < 2; i++)
        assert_float_equal(ts_light_distribution_pmf(&s->light_distribution, (ts_vec3){0, 0, 0}, i), 0.5f, 1e-7);

    /* convert says uniform; its document renders the same pixels; without the key JSON's
     * default (power) selects 1 : 9. */
    char *json = NULL;
    size_t len = 0;
    ts_error err = {0};
    assert_int_equal(ts_scene_convert_pbrt_path(path, NULL, on_warning, &w, &json, &len, &err), TS_OK);
    cJSON *doc = cJSON_ParseWithLength(json, len);
    const cJSON *integ = cJSON_GetObjectItemCaseSensitive(doc, "integrator");
    assert_string_equal(cJSON_GetObjectItemCaseSensitive(integ, "type")->valuestring, "direct");
    assert_string_equal(cJSON_GetObjectItemCaseSensitive(integ, "strategy")->valuestring, "one");
    const cJSON *sel = cJSON_GetObjectItemCaseSensitive(integ, "light_sampling");
    assert_true(cJSON_IsString(sel));
    assert_string_equal(sel->valuestring, "uniform");
    ts_scene *b = NULL;
    if (ts_scene_load_text(json, len, ts_tmp_dir, "one", NULL, &b, &err)) fail_msg("%s", err.message);
    assert_same_pixels(s, b, 4);
    ts_scene_destroy(b);
    cJSON_DeleteItemFromObjectCaseSensitive((cJSON *)integ, "light_sampling");
    char *power_doc = cJSON_PrintUnformatted(doc);
    if (ts_scene_load_text(power_doc, strlen(power_doc), ts_tmp_dir, "one", NULL, &b, &err)) fail_msg("%s", err.message);
    assert_float_equal(ts_light_distribution_pmf(&b->light_distribution, (ts_vec3){0, 0, 0}, 0), 0.1f, 1e-6);
    assert_float_equal(ts_light_distribution_pmf(&b->light_distribution, (ts_vec3){0, 0, 0}, 1), 0.9f, 1e-6);
    ts_scene_destroy(b);
    free(power_doc);
    cJSON_Delete(doc);
    free(json);

    /* The image mean against the closed form. */
    const double lights[2][4] = {{0.3, 0.2, 1, 1}, {-0.5, -0.4, 2, 9}}; /* x, y, height, I */
    const int cells = 1024;
    double sum = 0;
    for (int j = 0; j < cells; j++)
        for (int i = 0; i < cells; i++) {
            double x = -1 + (i + 0.5) * 2.0 / cells, y = -1 + (j + 0.5) * 2.0 / cells;
            for (int k = 0; k < 2; k++) {
                double dx = x - lights[k][0], dy = y - lights[k][1], h = lights[k][2];
                double r2 = dx * dx + dy * dy + h * h;
                sum += lights[k][3] * h / (r2 * sqrt(r2));
            }
        }
    const double want = 0.5 / TS_PI_D * sum / ((double)cells * cells);
    ts_rs_blocks r;
    ts_rs_render(s, TS_SAMPLER_SOBOL, 7, 16, 16, 8, &r);
    double t = (r.image_mean - want) / r.image_se;
    print_message("directlighting one, uniform: image mean %.6f ± %.6f, closed form %.6f (t %.2f)\n", r.image_mean,
                  r.image_se, want, t);
    assert_true(r.image_se > 0);
    assert_true(ts_rs_student_two_sided(t, 15) >= 1e-3);
    ts_scene_destroy(s);
}

/* Materials: pbrt-v3's parameter names, defaults and roughness remapping. */
static void materials_mapped(void **state)
{
    (void)state;
    warnings w = {0};
    ts_scene *s =
        load("WorldBegin\n"
             "Material \"plastic\" \"rgb Kd\" [0.1 0.2 0.3] \"float roughness\" 0.3\n"
             "Shape \"sphere\"\n"
             "Material \"plastic\" \"float roughness\" 0.3 \"bool remaproughness\" \"false\"\n"
             "Shape \"sphere\"\n"
             "Material \"metal\"\nShape \"sphere\"\n"
             "Material \"glass\" \"float index\" 1.33\nShape \"sphere\"\n"
             "Material \"mirror\"\nShape \"sphere\"\n"
             "Material \"substrate\" \"float uroughness\" 0.2 \"float vroughness\" 0.2\nShape \"sphere\"\n"
             "Material \"matte\" \"spectrum Kd\" [300 0.5 800 0.5] \"float sigma\" 20\nShape \"sphere\"\n"
             "WorldEnd\n",
             &w);
    const ts_material *m[7];
    for (int i = 0; i < 7; i++)
        m[i] = &s->materials[s->shapes[i].material];
    assert_int_equal(m[0]->type, TS_MATERIAL_PLASTIC_PBRT3);
    assert_true(m[0]->diffuse.value.b == 0.3f && m[0]->specular.value.r == 0.25f);
    /* roughness as given; pbrt-v3's remapping is the builder's (remaproughness, default true) */
    assert_float_equal(m[0]->roughness.value, 0.3f, 0);
    assert_true(m[0]->remap_roughness);
    assert_float_equal(m[1]->roughness.value, 0.3f, 0);
    assert_false(m[1]->remap_roughness);
    assert_int_equal(m[2]->type, TS_MATERIAL_CONDUCTOR);
    ts_rgb eta, k;
    ts_spectrum_copper(&eta, &k);
    assert_true(m[2]->conductor_eta.value.r == eta.r && m[2]->conductor_k.value.b == k.b);
    /* copper: n falls and k rises toward the red */
    assert_true(eta.r < eta.b && k.r > k.b);
    assert_int_equal(m[3]->type, TS_MATERIAL_DIELECTRIC);
    assert_float_equal(m[3]->eta.value, 1.33f, 0);
    assert_float_equal(m[3]->roughness.value, 0, 0);
    assert_int_equal(m[4]->type, TS_MATERIAL_MIRROR);
    assert_float_equal(m[4]->reflectance.value.r, 0.9f, 0);
    assert_int_equal(m[5]->type, TS_MATERIAL_SUBSTRATE);
    assert_int_equal(m[6]->type, TS_MATERIAL_DIFFUSE);
    assert_float_equal(m[6]->sigma_deg.value, 20, 0);
    ts_scene_destroy(s);
}


/* A material parameter naming a texture takes the scene's texture (texture_pbrt.h); a
 * constant texture is its value; so does a roughness, and bumpmap is the material's bump. */
static void textured_parameters(void **state)
{
    (void)state;
    warnings w = {0};
    ts_scene *s = load("WorldBegin\n"
                       "Texture \"checks\" \"color\" \"checkerboard\" \"float uscale\" 4\n"
                       "Texture \"grey\" \"float\" \"constant\" \"float value\" 0.25\n"
                       "Material \"matte\" \"texture Kd\" \"checks\" \"texture sigma\" \"grey\"\n"
                       "Shape \"sphere\"\nWorldEnd\n",
                       &w);
    const ts_material *m = &s->materials[s->shapes[0].material];
    assert_non_null(m->reflectance.tex);
    assert_null(m->sigma_deg.tex);
    assert_float_equal(m->sigma_deg.value, 0.25f, 0);
    ts_scene_destroy(s);
    w = (warnings){0};
    s = load("WorldBegin\nTexture \"r\" \"float\" \"fbm\"\n"
             "Texture \"c\" \"float\" \"constant\" \"float value\" 0.2\n"
             "Material \"metal\" \"texture roughness\" \"r\" \"texture bumpmap\" \"r\"\nShape \"sphere\"\n"
             "Material \"matte\" \"texture bumpmap\" \"c\"\nShape \"sphere\"\nWorldEnd\n",
             &w);
    m = &s->materials[s->shapes[0].material];
    assert_non_null(m->roughness.tex);
    assert_true(m->remap_roughness);
    assert_ptr_equal(m->bump, m->roughness.tex); /* the one texture "r" */
    assert_true(m->textured);
    /* a constant displacement has no gradient: no bump map, and nothing "ignored" */
    assert_null(s->materials[s->shapes[1].material].bump);
    assert_int_equal(w.n, 0);
    ts_scene_destroy(s);
    expect_error("WorldBegin\nTexture \"k\" \"color\" \"checkerboard\"\n"
                 "Material \"matte\" \"texture bumpmap\" \"k\"\nShape \"sphere\"\nWorldEnd\n",
                 "t.pbrt:3:18: Material \"matte\": \"texture bumpmap\" names no float texture \"k\" in scope");
}

/* uber, translucent and mix with pbrt-v3's parameter names and defaults; anisotropic
 * roughness where pbrt-v3 reads it (metal's u/vroughness each defaulting to roughness, uber's
 * vroughness to uroughness, substrate's each to 0.1). */
static void pbrt3_materials_mapped(void **state)
{
    (void)state;
    warnings w = {0};
    ts_scene *s =
        load("WorldBegin\n"
             "Material \"uber\" \"rgb Kd\" [0.1 0.2 0.3] \"rgb Kr\" [0.4 0.4 0.4] \"float index\" 1.7\n"
             "  \"float vroughness\" 0.05 \"rgb opacity\" [0.5 0.6 0.7] \"bool remaproughness\" \"false\"\n"
             "Shape \"sphere\"\n"
             "Material \"translucent\" \"rgb reflect\" [0.3 0.3 0.3] \"float roughness\" 0.2\nShape \"sphere\"\n"
             "MakeNamedMaterial \"a\" \"string type\" \"plastic\"\n"
             "MakeNamedMaterial \"b\" \"string type\" \"metal\" \"float uroughness\" 0.1\n"
             "MakeNamedMaterial \"m\" \"string type\" \"mix\" \"string namedmaterial1\" \"b\"\n"
             "  \"string namedmaterial2\" \"a\" \"rgb amount\" [0.2 0.3 0.4]\n"
             "NamedMaterial \"m\"\nShape \"sphere\"\n"
             "Material \"glass\" \"float uroughness\" 0.3 \"float vroughness\" 0.1\nShape \"sphere\"\n"
             "WorldEnd\n",
             &w);
    const ts_material *u = &s->materials[s->shapes[0].material];
    assert_int_equal(u->type, TS_MATERIAL_UBER);
    assert_true(u->diffuse.value.g == 0.2f && u->specular.value.r == 0.25f && u->reflectance.value.b == 0.4f &&
                u->transmittance.value.r == 0 && u->opacity.value.b == 0.7f);
    assert_float_equal(u->eta.value, 1.7f, 0);
    assert_true(u->has_vroughness && u->roughness.value == 0.1f && u->vroughness.value == 0.05f);
    assert_false(u->remap_roughness);
    const ts_material *t = &s->materials[s->shapes[1].material];
    assert_int_equal(t->type, TS_MATERIAL_TRANSLUCENT);
    assert_true(t->reflectance.value.r == 0.3f && t->transmittance.value.r == 0.5f && t->diffuse.value.r == 0.25f);
    assert_true(t->roughness.value == 0.2f && t->remap_roughness && !t->has_vroughness);
    const ts_material *x = &s->materials[s->shapes[2].material];
    assert_int_equal(x->type, TS_MATERIAL_MIX);
    assert_true(x->amount.value.r == 0.2f && x->amount.value.b == 0.4f);
    assert_int_equal(x->mix[0]->type, TS_MATERIAL_CONDUCTOR); /* namedmaterial1 carries amount */
    assert_int_equal(x->mix[1]->type, TS_MATERIAL_PLASTIC_PBRT3);
    assert_true(x->mix[0]->has_vroughness && x->mix[0]->roughness.value == 0.1f &&
                x->mix[0]->vroughness.value == 0.01f);
    const ts_material *g = &s->materials[s->shapes[3].material];
    assert_true(g->has_vroughness && g->roughness.value == 0.3f && g->vroughness.value == 0.1f);
    ts_scene_destroy(s);
    /* substrate: uroughness and vroughness each default to 0.1 (pbrt-v3's, not to each other). */
    s = load("WorldBegin\nMaterial \"substrate\" \"float uroughness\" 0.3\nShape \"sphere\"\n"
             "Material \"substrate\" \"float vroughness\" 0.1\nShape \"sphere\"\nWorldEnd\n",
             &w);
    const ts_material *sa = &s->materials[s->shapes[0].material], *sb = &s->materials[s->shapes[1].material];
    assert_true(sa->type == TS_MATERIAL_SUBSTRATE && sa->has_vroughness && sa->roughness.value == 0.3f &&
                sa->vroughness.value == 0.1f && sa->remap_roughness);
    assert_true(!sb->has_vroughness && sb->roughness.value == 0.1f);
    ts_scene_destroy(s);
    /* uber: a missing vroughness takes uroughness's value (pbrt-v3's roughv = roughu), not
     * roughness's as metal's does: (0.3, 0.3), not (0.3, 0.1). */
    s = load("WorldBegin\nMaterial \"uber\" \"float uroughness\" 0.3\nShape \"sphere\"\n"
             "Material \"metal\" \"float uroughness\" 0.3\nShape \"sphere\"\nWorldEnd\n",
             &w);
    const ts_material *ua = &s->materials[s->shapes[0].material], *ma = &s->materials[s->shapes[1].material];
    assert_true(ua->type == TS_MATERIAL_UBER && !ua->has_vroughness && ua->roughness.value == 0.3f);
    assert_true(ma->type == TS_MATERIAL_CONDUCTOR && ma->has_vroughness && ma->roughness.value == 0.3f &&
                ma->vroughness.value == 0.01f);
    ts_scene_destroy(s);
    expect_error("WorldBegin\nMakeNamedMaterial \"n\" \"string type\" \"none\"\n"
                 "MakeNamedMaterial \"a\" \"string type\" \"matte\"\n"
                 "MakeNamedMaterial \"m\" \"string type\" \"mix\" \"string namedmaterial1\" \"a\"\n"
                 "  \"string namedmaterial2\" \"n\"\nNamedMaterial \"m\"\nShape \"sphere\"\nWorldEnd\n",
                 "t.pbrt:5:3: MakeNamedMaterial \"m\": \"string namedmaterial2\" names material \"n\" of type "
                 "\"none\" (no surface), which cannot be mixed");
}

/* A mix with amount 1 is its namedmaterial1 (namedmaterial2's lobes scaled by 0 are left
 * out): it renders bit-identically to that material alone; weighting namedmaterial2
 * instead renders the matte. */
static void mix_amount_weights_first(void **state)
{
    (void)state;
    const char *head = "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 30\n"
                       "Film \"image\" \"integer xresolution\" 8 \"integer yresolution\" 8\n"
                       "WorldBegin\nLightSource \"point\" \"point from\" [2 2 5] \"rgb I\" [20 20 20]\n"
                       "MakeNamedMaterial \"p\" \"string type\" \"plastic\" \"rgb Kd\" [0.1 0.5 0.2] \"float "
                       "roughness\" 0.05\n"
                       "MakeNamedMaterial \"d\" \"string type\" \"matte\" \"rgb Kd\" [0.7 0.1 0.1]\n";
    char a[2048], b[2048];
    snprintf(a, sizeof a,
             "%sMakeNamedMaterial \"m\" \"string type\" \"mix\" \"string namedmaterial1\" \"p\" \"string "
             "namedmaterial2\" \"d\" \"float amount\" 1\nNamedMaterial \"m\"\nShape \"sphere\"\nWorldEnd\n",
             head);
    snprintf(b, sizeof b, "%sNamedMaterial \"p\"\nShape \"sphere\"\nWorldEnd\n", head);
    warnings w = {0};
    ts_scene *sa = load(a, &w), *sb = load(b, &w);
    assert_same_pixels(sa, sb, 4);
    ts_scene_destroy(sa);
    ts_scene_destroy(sb);
}

/* ObjectInstance places an object's shapes by the CTM at the instance: under a white sky
 * the pixel looking at where an instance put a sphere is darker than the sky. */
static void instances_placed(void **state)
{
    (void)state;
    const char *fmt = "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 10\n"
                      "Film \"image\" \"integer xresolution\" 4 \"integer yresolution\" 4\n"
                      "Integrator \"path\" \"integer maxdepth\" 1\nWorldBegin\n"
                      "LightSource \"infinite\" \"rgb L\" [1 1 1]\n"
                      "ObjectBegin \"ball\" Shape \"sphere\" \"float radius\" 0.3 ObjectEnd\n"
                      "Translate %s ObjectInstance \"ball\"\nWorldEnd\n";
    const char *where[] = {"0 0 0", "3 0 0"};
    float v[2];
    for (int i = 0; i < 2; i++) {
        char text[1024];
        snprintf(text, sizeof text, fmt, where[i]);
        warnings w = {0};
        ts_scene *s = load(text, &w);
        ts_error err = {0};
        ts_film *f = ts_film_create(4, 4, 0, 0, 4, 4, &err);
        ts_render_stats st = {0};
        ts_render_request req = {s, s->integrator.type, f, 0, 16, 1, NULL, NULL, NULL};
        assert_int_equal(ts_render(&req, &st, &err), TS_OK);
        v[i] = ts_film_pixel_rgb(f, 2, 2).g;
        ts_film_destroy(f);
        ts_scene_destroy(s);
    }
    assert_true(v[0] < 0.9f);          /* the matte ball, lit by the sky: at most 0.5 */
    assert_float_equal(v[1], 1, 1e-6); /* moved out of view: the sky */
}

/* Every parameter nothing reads is warned about, once per message. */
static void unused_parameters_warned(void **state)
{
    (void)state;
    warnings w = {0};
    ts_scene *s = load("WorldBegin\nShape \"sphere\" \"float radius\" 1 \"float bogus\" 2\n"
                       "Shape \"sphere\" \"float bogus\" 2\nWorldEnd\n",
                       &w);
    assert_int_equal(w.n, 2); /* the first, then the count of repeats */
    assert_string_equal(w.last, "1 more warnings like the ones above were not repeated");
    ts_scene_destroy(s);
    w = (warnings){0};
    s = load("WorldBegin\nShape \"sphere\" \"float bogus\" 2\nWorldEnd\n", &w);
    assert_int_equal(w.n, 1);
    assert_string_equal(w.last, "t.pbrt:2:16: Shape \"sphere\": \"float bogus\" is not used");
    ts_scene_destroy(s);
}

/* The same scene in two films: each pixel's value, bit for bit. */
static void assert_same_pixels(const ts_scene *a, const ts_scene *b, uint32_t spp)
{
    assert_int_equal(a->width, b->width);
    assert_int_equal(a->height, b->height);
    ts_error err = {0};
    ts_film *f[2];
    const ts_scene *s[2] = {a, b};
    for (int i = 0; i < 2; i++) {
        f[i] = ts_film_create(s[i]->width, s[i]->height, s[i]->crop_x0, s[i]->crop_y0,
                              s[i]->crop_x1 - s[i]->crop_x0, s[i]->crop_y1 - s[i]->crop_y0, &err);
        assert_non_null(f[i]);
        ts_render_stats st = {0};
        ts_render_request req = {s[i], s[i]->integrator.type, f[i], 0, spp, 1, NULL, NULL, NULL};
        assert_int_equal(ts_render(&req, &st, &err), TS_OK);
    }
    int differ = 0;
    double sum = 0;
    for (int y = a->crop_y0; y < a->crop_y1; y++)
        for (int x = a->crop_x0; x < a->crop_x1; x++) {
            ts_rgb p = ts_film_pixel_rgb(f[0], x, y), q = ts_film_pixel_rgb(f[1], x, y);
            differ += memcmp(&p, &q, sizeof p) != 0;
            sum += p.r + p.g + p.b;
        }
    assert_int_equal(differ, 0);
    assert_true(sum > 0); /* the scene is not black: the comparison means something */
    ts_film_destroy(f[0]);
    ts_film_destroy(f[1]);
}

/* pbrt-v3's media: MakeNamedMedium (homogeneous with a preset and scale, heterogeneous with
 * its grid under the CTM), MediumInterface on a surface-less sphere, the camera's medium;
 * the parameters continue across an Include's end (cloud.pbrt's sigma_a, sigma_s after
 * its Include); convert writes them and the conversion renders the same pixels; path warns
 * that it does not simulate them; undefined names and bad values are refused at
 * file:line:column. */
static const char media_scene[] =
    "Integrator \"volpath\" \"integer maxdepth\" 6\n"
    "LookAt 0 0 5  0 0 0  0 1 0\n"
    "MakeNamedMedium \"haze\" \"string type\" \"homogeneous\" \"string preset\" \"Ketchup\" \"float scale\" 0.01\n"
    "MediumInterface \"\" \"haze\"\n"
    "Camera \"perspective\" \"float fov\" 40\n"
    "Film \"image\" \"integer xresolution\" 12 \"integer yresolution\" 8\n"
    "Sampler \"sobol\" \"integer pixelsamples\" 2\n"
    "WorldBegin\n"
    "LightSource \"infinite\" \"rgb L\" [0.5 0.5 0.5]\n"
    "AttributeBegin\n"
    "  Translate -0.5 -0.5 -0.5\n"
    "  Include \"grid.pbrt\" \"rgb sigma_a\" [1 1 1] \"rgb sigma_s\" [3 3 3]\n"
    "AttributeEnd\n"
    "AttributeBegin\n"
    "  Material \"\"\n"
    "  MediumInterface \"smoke\" \"haze\"\n"
    "  Shape \"sphere\" \"float radius\" 0.8\n"
    "AttributeEnd\n"
    "Shape \"disk\" \"float radius\" 3 \"float height\" -1\n"
    "WorldEnd\n";

static void media_mapped(void **state)
{
    (void)state;
    char path[512], grid[512];
    write_file("grid.pbrt",
               "MakeNamedMedium \"smoke\" \"string type\" \"heterogeneous\" \"integer nx\" 2 \"integer ny\" 2 "
               "\"integer nz\" 2 \"float density\" [0 1 0.5 1 1 0.25 0 1] \"point p0\" [0 0 0] \"point p1\" [1 1 2] "
               "\"float g\" -0.3\n",
               grid, sizeof grid);
    write_file("media.pbrt", media_scene, path, sizeof path);
    ts_scene *a = NULL, *b = NULL;
    ts_error err = {0};
    warnings w = {0};
    if (ts_scene_load_path(path, NULL, on_warning, &w, &a, &err)) fail_msg("%s", err.message);
    assert_int_equal(a->integrator.type, TS_INTEGRATOR_VOLPATH);
    assert_int_equal(a->n_media, 2);
    assert_int_equal(a->camera_medium, 0);
    assert_float_equal(a->media[0].sigma_s.r, 0.0018f, 1e-7); /* Ketchup's σ′s 0.18 × 0.01 */
    const ts_medium *g = &a->media[1];
    assert_int_equal(g->type, TS_MEDIUM_GRID);
    assert_float_equal(g->sigma_s.g, 3, 0); /* the parameters after the Include */
    assert_float_equal(g->g, -0.3f, 0);
    assert_float_equal(ts_medium_density(g, (ts_vec3){0.25f - 0.5f, 0.25f - 0.5f, 0.5f - 0.5f}), 0, 1e-6);
    assert_float_equal(ts_medium_density(g, (ts_vec3){0.75f - 0.5f, 0.25f - 0.5f, 0.5f - 0.5f}), 1, 1e-6);
    assert_true(a->shapes[0].material == TS_NONE && a->shapes[0].medium_transition);
    assert_int_equal(a->shapes[0].medium_inside, 1);
    assert_int_equal(a->shapes[0].medium_outside, 0);
    /* The disk: the MediumInterface "" "haze" of the options block still holds (pbrt-v3's
     * WorldBegin keeps the graphics state): vacuum behind it, haze in front. */
    assert_true(a->shapes[1].medium_transition);
    assert_int_equal(a->shapes[1].medium_inside, TS_NONE);
    assert_int_equal(a->shapes[1].medium_outside, 0);
    char *json = NULL;
    size_t len = 0;
    assert_int_equal(ts_scene_convert_pbrt_path(path, NULL, on_warning, &w, &json, &len, &err), TS_OK);
    if (ts_scene_load_text(json, len, ts_tmp_dir, "media", NULL, &b, &err)) fail_msg("%s", err.message);
    assert_same_pixels(a, b, 2);
    free(json);
    ts_scene_destroy(a);
    ts_scene_destroy(b);

    char text[2048];
    snprintf(text, sizeof text, "%s", media_scene);
    char *integ = strstr(text, "\"volpath\"");
    memcpy(integ, "\"path\"   ", 9);
    write_file("media-path.pbrt", text, path, sizeof path);
    w = (warnings){0};
    if (ts_scene_load_path(path, NULL, on_warning, &w, &a, &err)) fail_msg("%s", err.message);
    assert_non_null(strstr(w.last, "does not simulate the scene's participating media")); /* the last warning */
    ts_scene_destroy(a);

    expect_error("MediumInterface \"\" \"fog\"\nCamera \"perspective\"\nWorldBegin\nWorldEnd\n",
                 "t.pbrt:2:1: Camera \"perspective\" is in medium \"fog\" (MediumInterface), which no MakeNamedMedium "
                 "defines");
    expect_error("WorldBegin\nMakeNamedMedium \"a\" \"string type\" \"homogeneous\"\nMediumInterface \"b\" \"a\"\n"
                 "Shape \"sphere\"\nWorldEnd\n",
                 "t.pbrt:4:1: Shape \"sphere\" is inside MediumInterface medium \"b\", which no MakeNamedMedium "
                 "defines");
    expect_error("WorldBegin\nMakeNamedMedium \"a\" \"string type\" \"heterogeneous\" \"integer nx\" 2 "
                 "\"float density\" [1 2 3] \"rgb sigma_a\" [1 1 1] \"rgb sigma_s\" [1 1 1]\nWorldEnd\n",
                 "t.pbrt:2:1: MakeNamedMedium \"a\": density: 3 values, expected nx·ny·nz = 2·1·1 = 2");
    /* A product beyond 2^64 must not wrap round to the count given. */
    expect_error("WorldBegin\nMakeNamedMedium \"a\" \"string type\" \"heterogeneous\" \"integer nx\" 2147483647 "
                 "\"integer ny\" 2147483647 \"integer nz\" 2147483647 \"float density\" [1] \"rgb sigma_a\" [1 1 1] "
                 "\"rgb sigma_s\" [1 1 1]\nWorldEnd\n",
                 "t.pbrt:2:1: MakeNamedMedium \"a\": density: 1 values, expected nx·ny·nz = 2147483647·2147483647·2147483647");
    expect_error("WorldBegin\nMakeNamedMedium \"a\" \"string type\" \"homogeneous\" \"string preset\" \"Jam\"\nWorldEnd\n",
                 "t.pbrt:2:1: MakeNamedMedium \"a\": preset: unknown medium preset \"Jam\" (pbrt-v3's names, e.g. "
                 "\"Wholemilk\", \"Ketchup\", \"Espresso\")");
    expect_error("WorldBegin\nMakeNamedMedium \"a\" \"string type\" \"homogeneous\" \"rgb sigma_s\" [1 -1 1]\nWorldEnd\n",
                 "t.pbrt:2:1: MakeNamedMedium \"a\": sigma_s: expected finite RGB ≥ 0, got (1, -1, 1)");
}

/* A scene using every mapping, for the round trips. */
static const char every_mapping[] =
    "LookAt 0 1 6  0 0.5 0  0 1 0\n"
    "Camera \"perspective\" \"float fov\" 40 \"float lensradius\" 0.02 \"float focaldistance\" 6\n"
    "Film \"image\" \"integer xresolution\" 24 \"integer yresolution\" 16 \"float cropwindow\" [0.1 0.9 0 "
    "1]\n"
    "PixelFilter \"mitchell\" \"float B\" 0.5 \"float C\" 0.25\n"
    "Sampler \"halton\" \"integer pixelsamples\" 4\n"
    "Integrator \"path\" \"integer maxdepth\" 4\n"
    "WorldBegin\n"
    "LightSource \"infinite\" \"blackbody L\" [5500 0.3]\n"
    "LightSource \"spot\" \"point from\" [0 4 0] \"point to\" [0 0 0] \"rgb I\" [4 4 4]\n"
    "LightSource \"distant\" \"point from\" [1 1 1] \"point to\" [0 0 0] \"rgb L\" [0.5 0.4 0.3]\n"
    "AttributeBegin Translate 0 3 0 AreaLightSource \"diffuse\" \"rgb L\" [3 3 3] \"bool twosided\" "
    "\"true\"\n"
    "  Shape \"disk\" \"float radius\" 0.5 AttributeEnd\n"
    "Material \"plastic\" \"rgb Kd\" [0.5 0.3 0.2]\n"
    "Shape \"trianglemesh\" \"point P\" [-5 0 -5 5 0 -5 5 0 5 -5 0 5] \"integer indices\" [0 1 2 0 2 3]"
    " \"float uv\" [0 0 1 0 1 1 0 1]\n"
    "AttributeBegin Translate -1 0.5 0 Material \"glass\" Shape \"sphere\" \"float radius\" 0.5 "
    "AttributeEnd\n"
    "AttributeBegin Translate 0 1.5 -1 Shape \"sphere\" \"float radius\" 0.4 \"float zmin\" -0.2 \"float "
    "phimax\" 270\n"
    "  ReverseOrientation AreaLightSource \"diffuse\" \"rgb L\" [1 2 1]\n"
    "  Shape \"disk\" \"float radius\" 0.3 \"float phimax\" 200 \"float height\" 0.2\n"
    "  Shape \"cylinder\" \"float radius\" 0.2 \"float zmin\" 0.5 \"float zmax\" -0.1 \"float phimax\" 120\n"
    "AttributeEnd\n"
    "AttributeBegin Translate 2 1 -1 Scale 0.5 0.5 0.5 Material \"mirror\"\n"
    "  Shape \"loopsubdiv\" \"integer nlevels\" 2 \"point P\" [1 1 1 -1 -1 1 -1 1 -1 1 -1 -1]"
    " \"integer indices\" [0 1 2 0 3 1 0 2 3 1 3 2] AttributeEnd\n"
    "ObjectBegin \"pair\" Material \"matte\" \"rgb Kd\" [0.2 0.6 0.2] Translate 0 0.15 0\n"
    "  Shape \"sphere\" \"float radius\" 0.15 Translate 0.4 0 0 Shape \"sphere\" \"float radius\" 0.1 "
    "ObjectEnd\n"
    "AttributeBegin Translate -2 0 1 ObjectInstance \"pair\" AttributeEnd\n"
    "AttributeBegin Translate 1.5 0 1.5 Rotate 30 0 1 0 ObjectInstance \"pair\" AttributeEnd\n"
    "AttributeBegin Translate 1 0.5 0 Rotate 90 1 0 0 Material \"metal\" \"float roughness\" 0.1\n"
    "  Shape \"cylinder\" \"float radius\" 0.3 \"float zmin\" -0.5 \"float zmax\" 0.5 AttributeEnd\n"
    "MakeNamedMaterial \"bm\" \"string type\" \"metal\" \"float uroughness\" 0.05 \"float vroughness\" 0.3\n"
    "MakeNamedMaterial \"tl\" \"string type\" \"translucent\" \"rgb Kd\" [0.6 0.5 0.4] \"float roughness\" 0.2\n"
    "MakeNamedMaterial \"mx\" \"string type\" \"mix\" \"string namedmaterial1\" \"bm\"\n"
    "  \"string namedmaterial2\" \"tl\" \"rgb amount\" [0.3 0.5 0.7]\n"
    "AttributeBegin Translate -0.5 0.3 1.5 NamedMaterial \"mx\" Shape \"sphere\" \"float radius\" 0.3 AttributeEnd\n"
    "AttributeBegin Translate 0.5 0.3 1.5 Material \"uber\" \"rgb Kr\" [0.2 0.2 0.2] \"rgb Kt\" [0.3 0.3 0.3]\n"
    "  \"rgb opacity\" [0.8 0.9 1] \"float index\" 1.4 \"float vroughness\" 0.4 Shape \"sphere\" \"float radius\" 0.2\n"
    "AttributeEnd\n"
    "AttributeBegin Translate 0 0.3 1 Scale 0.3 0.3 0.3 ReverseOrientation Material \"substrate\"\n"
    "  Shape \"trianglemesh\" \"point P\" [0 0 0 1 0 0 0 1 0 0 0 1] \"integer indices\" [0 1 2 0 1 3 0 2 3 1 "
    "2 3]\n"
    "  \"normal N\" [-1 -1 -1 1 0 0 0 1 0 0 0 1]\n"
    "AttributeEnd\nWorldEnd\n";

/* `convert`'s document loads as JSON v1 and renders bit-identically to the .pbrt. */
static void convert_round_trip(void **state)
{
    (void)state;
    char path[512];
    write_file("every.pbrt", every_mapping, path, sizeof path);
    warnings w = {0};
    char *json = NULL;
    size_t len = 0;
    ts_error err = {0};
    assert_int_equal(ts_scene_convert_pbrt_path(path, NULL, on_warning, &w, &json, &len, &err), TS_OK);
    ts_scene *a = NULL, *b = NULL;
    assert_int_equal(ts_scene_load_path(path, NULL, NULL, NULL, &a, &err), TS_OK);
    if (ts_scene_load_text(json, len, ts_tmp_dir, "every", NULL, &b, &err)) fail_msg("%s", err.message);
    assert_string_equal(a->name, b->name);
    assert_int_equal(a->n_shapes, b->n_shapes);
    assert_int_equal(a->n_lights, b->n_lights);
    assert_same_pixels(a, b, 4);
    free(json);
    ts_scene_destroy(a);
    ts_scene_destroy(b);
}

/* A .pbrt name of bytes that are not UTF-8 loads (pbrt-v3 takes any bytes), and `convert`
 * refuses it with a sentence, not a document JSON cannot parse (found by fuzz_pbrt_import). */
static void convert_refuses_non_utf8(void **state)
{
    (void)state;
    const char *doc = "LookAt 0 3 4  0 0 0  0 1 0\nCamera \"perspective\"\nWorldBegin\n"
                      "LightSource \"distant\" \"rgb L\" [1 1 1]\n"
                      "Texture \"bump\\t\xff\xfe\" \"float\" \"fbm\"\n"
                      "Material \"matte\" \"texture sigma\" \"bump\\t\xff\xfe\"\nShape \"sphere\"\nWorldEnd\n";
    char path[512];
    write_file("latin.pbrt", doc, path, sizeof path);
    ts_scene *a = NULL;
    ts_error err = {0};
    if (ts_scene_load_path(path, NULL, NULL, NULL, &a, &err)) fail_msg("%s", err.message);
    ts_scene_destroy(a);
    char *json = NULL;
    size_t len = 0;
    assert_int_equal(ts_scene_convert_pbrt_path(path, NULL, NULL, NULL, &json, &len, &err), TS_ERR_UNSUPPORTED);
    assert_null(json);
    if (!strstr(err.message, "not UTF-8 text")) fail_msg("%s", err.message);
}

/* The same through the command line: render .pbrt and render of its conversion write the
 * same EXR pixels. */
static void cli_convert_and_render(void **state)
{
    (void)state;
    const char *bin = getenv("TS_BINARY");
    if (!bin) skip();
    char pbrt[512], cmd[4096];
    write_file("cli.pbrt", every_mapping, pbrt, sizeof pbrt);
    snprintf(cmd, sizeof cmd,
             "'%s' convert '%s' -o '%s/cli.json' --quiet && '%s' render '%s' --spp 2 --threads 2 --quiet -o "
             "'%s/a.exr' 2>/dev/null && '%s' render '%s/cli.json' --spp 2 --threads 1 --quiet -o '%s/b.exr'",
             bin, pbrt, ts_tmp_dir, bin, pbrt, ts_tmp_dir, bin, ts_tmp_dir, ts_tmp_dir);
    assert_int_equal(system(cmd), 0);
    char pa[512], pb[512];
    snprintf(pa, sizeof pa, "%s/a.exr", ts_tmp_dir);
    snprintf(pb, sizeof pb, "%s/b.exr", ts_tmp_dir);
    ts_image ia = {0}, ib = {0};
    ts_error err = {0};
    assert_int_equal(ts_exr_read(pa, &ia, &err), TS_OK);
    assert_int_equal(ts_exr_read(pb, &ib, &err), TS_OK);
    assert_int_equal(ia.width, ib.width);
    assert_int_equal(ia.n_channels, ib.n_channels);
    assert_memory_equal(ia.data, ib.data, (size_t)ia.width * ia.height * ia.n_channels * sizeof(float));
    ts_image_fini(&ia);
    ts_image_fini(&ib);
    /* A refused scene: exit 1, the sentence with its position, nothing written. */
    write_file("bad.pbrt", "WorldBegin\nShape \"sphere\" \"float radius\" [1 2]\nWorldEnd\n", pbrt,
               sizeof pbrt);
    snprintf(cmd, sizeof cmd, "'%s' convert '%s' -o '%s/bad.json' 2>'%s/err.txt'", bin, pbrt, ts_tmp_dir,
             ts_tmp_dir);
    int rc = system(cmd);
    assert_true(WIFEXITED(rc) && WEXITSTATUS(rc) == 1);
    snprintf(pa, sizeof pa, "%s/bad.json", ts_tmp_dir);
    assert_int_not_equal(access(pa, F_OK), 0);
    snprintf(pa, sizeof pa, "%s/err.txt", ts_tmp_dir);
    FILE *f = fopen(pa, "r");
    char line[1024] = "";
    assert_non_null(fgets(line, sizeof line, f));
    fclose(f);
    assert_non_null(strstr(line, "bad.pbrt:2:16: Shape \"sphere\": \"float radius\" expects 1 value, got 2"));
}

/* Every texture class, mapping and textured parameter, for the textured round trip. */
static const char every_texture[] =
    "LookAt 0 1.2 5  0 0.4 0  0 1 0\n"
    "Camera \"perspective\" \"float fov\" 45\n"
    "Film \"image\" \"integer xresolution\" 32 \"integer yresolution\" 20\n"
    "Sampler \"sobol\" \"integer pixelsamples\" 4\n"
    "Integrator \"path\" \"integer maxdepth\" 3\n"
    "WorldBegin\n"
    "LightSource \"infinite\" \"rgb L\" [0.6 0.6 0.6]\n"
    "LightSource \"point\" \"point from\" [1 3 2] \"rgb I\" [6 6 6]\n"
    "Texture \"img\" \"color\" \"imagemap\" \"string filename\" \"img.pfm\" \"float uscale\" 2 \"string wrap\" "
    "\"clamp\" \"bool trilinear\" \"true\"\n"
    "Texture \"imgf\" \"float\" \"imagemap\" \"string filename\" \"img.pfm\" \"float maxanisotropy\" 4 "
    "\"float scale\" 0.5 \"bool invert\" \"true\" \"float vdelta\" 0.25\n"
    "Texture \"checks\" \"color\" \"checkerboard\" \"float uscale\" 4 \"float vscale\" 3 \"rgb tex1\" [0.8 0.2 "
    "0.1] \"texture tex2\" \"img\"\n"
    "TransformBegin Scale 3 3 3 Rotate 20 0 1 0\n"
    "  Texture \"checks\" \"color\" \"checkerboard\" \"integer dimension\" 3\n" /* the name again: "#2" */
    "  Texture \"f\" \"float\" \"fbm\" \"integer octaves\" 5 \"float roughness\" 0.6\n"
    "  Texture \"w\" \"float\" \"wrinkled\"\n"
    "  Texture \"wi\" \"float\" \"windy\"\n"
    "  Texture \"mb\" \"color\" \"marble\" \"float scale\" 2 \"float variation\" 0.5\n"
    "TransformEnd\n"
    "TransformBegin Translate 0.1 0.4 0 Rotate 30 1 0 0\n"
    "  Texture \"sph\" \"float\" \"bilerp\" \"string mapping\" \"spherical\" \"float v00\" 0.2 \"float v11\" 0.7\n"
    "  Texture \"cyl\" \"color\" \"uv\" \"string mapping\" \"cylindrical\"\n"
    "TransformEnd\n"
    "Texture \"pl\" \"color\" \"dots\" \"string mapping\" \"planar\" \"vector v1\" [1 0 1] \"vector v2\" [0 1 0] "
    "\"float udelta\" 0.3 \"rgb inside\" [0.9 0.8 0.1]\n"
    "Texture \"sc\" \"color\" \"scale\" \"texture tex1\" \"pl\" \"rgb tex2\" [0.5 0.7 0.9]\n"
    "Texture \"mx\" \"color\" \"mix\" \"texture tex1\" \"checks\" \"texture tex2\" \"mb\" \"texture amount\" \"f\"\n"
    "Texture \"bl\" \"color\" \"bilerp\" \"rgb v00\" [0.1 0.2 0.3]\n"
    "Texture \"none\" \"color\" \"checkerboard\" \"string aamode\" \"none\" \"float uscale\" 8\n"
    "Material \"matte\" \"texture Kd\" \"img\"\n"
    "Shape \"trianglemesh\" \"point P\" [-4 0 -4 4 0 -4 4 0 4 -4 0 4] \"integer indices\" [0 1 2 0 2 3]"
    " \"float uv\" [0 0 1 0 1 1 0 1]\n"
    "MakeNamedMaterial \"a\" \"string type\" \"matte\" \"texture Kd\" \"mx\" \"texture sigma\" \"w\" \"texture "
    "bumpmap\" \"wi\"\n"
    "MakeNamedMaterial \"b\" \"string type\" \"plastic\" \"texture Kd\" \"sc\" \"texture Ks\" \"none\" \"texture "
    "roughness\" \"imgf\" \"texture bumpmap\" \"f\"\n"
    "MakeNamedMaterial \"m\" \"string type\" \"mix\" \"string namedmaterial1\" \"a\" \"string namedmaterial2\" "
    "\"b\" \"texture amount\" \"cyl\"\n"
    "AttributeBegin Translate -1.4 0.4 0 NamedMaterial \"m\" Shape \"sphere\" \"float radius\" 0.4 AttributeEnd\n"
    "AttributeBegin Translate -0.5 0.4 0.5 Material \"metal\" \"texture uroughness\" \"sph\" \"texture "
    "vroughness\" \"w\"\n"
    "  Shape \"sphere\" \"float radius\" 0.35 AttributeEnd\n"
    "AttributeBegin Translate 0.4 0.4 0.6 Material \"glass\" \"texture Kr\" \"bl\" \"texture eta\" \"sph\"\n"
    "  Shape \"sphere\" \"float radius\" 0.3 AttributeEnd\n"
    "AttributeBegin Translate 1.2 0.4 0 Material \"uber\" \"texture opacity\" \"checks\" \"texture Kd\" \"pl\" "
    "\"texture bumpmap\" \"imgf\"\n"
    "  Shape \"sphere\" \"float radius\" 0.4 AttributeEnd\n"
    "AttributeBegin Translate 0.3 1.2 -0.8 Material \"substrate\" \"texture Kd\" \"mb\" \"texture bumpmap\" "
    "\"sph\"\n"
    "  Shape \"sphere\" \"float radius\" 0.35 AttributeEnd\n"
    "AttributeBegin Translate -0.6 1.2 -0.8 Material \"translucent\" \"texture Kd\" \"bl\" \"texture reflect\" "
    "\"cyl\"\n"
    "  Shape \"sphere\" \"float radius\" 0.35 AttributeEnd\n"
    "WorldEnd\n";

/* Textures through convert: the document holds every texture of the scene (the name given
 * twice written as "checks#2"), material parameters name them, and it renders
 * bit-identically to the .pbrt. A negative colour constant, which v1 cannot hold, is
 * refused with its position. */
static void convert_textures_round_trip(void **state)
{
    (void)state;
    /* A 4 × 3 RGB PFM (bottom row first) of distinct values. */
    char pfm[512];
    snprintf(pfm, sizeof pfm, "%s/img.pfm", ts_tmp_dir);
    FILE *f = fopen(pfm, "wb");
    assert_non_null(f);
    fprintf(f, "PF\n4 3\n-1.0\n");
    for (int i = 0; i < 36; i++) {
        float v = 0.05f + 0.025f * (float)i;
        assert_int_equal(fwrite(&v, sizeof v, 1, f), 1);
    }
    assert_int_equal(fclose(f), 0);
    char path[512];
    write_file("tex.pbrt", every_texture, path, sizeof path);
    char *json = NULL;
    size_t len = 0;
    ts_error err = {0};
    if (ts_scene_convert_pbrt_path(path, NULL, NULL, NULL, &json, &len, &err)) fail_msg("%s", err.message);
    cJSON *doc = cJSON_Parse(json);
    assert_non_null(doc);
    const cJSON *tex = cJSON_GetObjectItemCaseSensitive(doc, "textures");
    assert_int_equal(cJSON_GetArraySize(tex), 15); /* the 15 Texture directives */
    const cJSON *c2 = cJSON_GetObjectItemCaseSensitive(tex, "checks#2");
    assert_non_null(c2);
    assert_int_equal(cJSON_GetArraySize(cJSON_GetObjectItemCaseSensitive(c2, "world_to_texture")), 16);
    const cJSON *mats = cJSON_GetObjectItemCaseSensitive(doc, "materials");
    const cJSON *b = cJSON_GetObjectItemCaseSensitive(mats, "b#2");
    assert_string_equal(cJSON_GetObjectItemCaseSensitive(b, "bumpmap")->valuestring, "f");
    assert_string_equal(cJSON_GetObjectItemCaseSensitive(b, "roughness")->valuestring, "imgf");
    cJSON_Delete(doc);
    ts_scene *sa = NULL, *sb = NULL;
    if (ts_scene_load_path(path, NULL, NULL, NULL, &sa, &err)) fail_msg("%s", err.message);
    if (ts_scene_load_text(json, len, ts_tmp_dir, "tex", NULL, &sb, &err)) fail_msg("%s", err.message);
    assert_true(sa->textured && sb->textured);
    assert_same_pixels(sa, sb, 4);
    free(json);
    ts_scene_destroy(sa);
    ts_scene_destroy(sb);

    write_file("neg.pbrt",
               "WorldBegin\nTexture \"n\" \"color\" \"scale\" \"rgb tex1\" [-1 0 0]\n"
               "Material \"matte\" \"texture Kd\" \"n\"\nShape \"sphere\"\nWorldEnd\n",
               path, sizeof path);
    assert_int_equal(ts_scene_convert_pbrt_path(path, NULL, NULL, NULL, &json, &len, &err), TS_ERR_UNSUPPORTED);
    assert_null(json);
    assert_non_null(strstr(err.message, "neg.pbrt:2:1: texture \"n\": its tex1 (-1, 0, 0) is a negative colour, "
                                        "which scene format v1 cannot hold"));
}

/* The digest: a function of the bytes read, not of the path; any byte changes it. */
static void digest_of_bytes(void **state)
{
    (void)state;
    char p1[512], p2[512], p3[512];
    write_file("d1.pbrt", every_mapping, p1, sizeof p1);
    write_file("d2.pbrt", every_mapping, p2, sizeof p2);
    char changed[sizeof every_mapping];
    memcpy(changed, every_mapping, sizeof changed);
    *strstr(changed, "fov\" 40") = 'F'; /* "Fov": another parameter, same length */
    write_file("d3.pbrt", changed, p3, sizeof p3);
    ts_scene *a, *b, *c;
    ts_error err = {0};
    assert_int_equal(ts_scene_load_path(p1, NULL, NULL, NULL, &a, &err), TS_OK);
    assert_int_equal(ts_scene_load_path(p2, NULL, NULL, NULL, &b, &err), TS_OK);
    assert_int_equal(ts_scene_load_path(p3, NULL, NULL, NULL, &c, &err), TS_OK);
    assert_string_equal(a->digest, b->digest);
    assert_string_not_equal(a->digest, c->digest);
    ts_scene_destroy(a);
    ts_scene_destroy(b);
    ts_scene_destroy(c);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(camera_lookat_orientation),
        cmocka_unit_test(camera_screen_window),
        cmocka_unit_test(camera_orthographic),
        cmocka_unit_test(filter_gaussian),
        cmocka_unit_test(film_scale_and_clamp),
        cmocka_unit_test(dots_swap_warned),
        cmocka_unit_test(named_material_unknown_kept),
        cmocka_unit_test(spectrum_equal_energy),
        cmocka_unit_test(error_sentences),
        cmocka_unit_test(lights_mapped),
        cmocka_unit_test(shapes_mapped),
        cmocka_unit_test(mesh_orientation),
        cmocka_unit_test(plymesh_normals_keep_lengths),
        cmocka_unit_test(directlighting_one_uniform),
        cmocka_unit_test(materials_mapped),
        cmocka_unit_test(textured_parameters),
        cmocka_unit_test(pbrt3_materials_mapped),
        cmocka_unit_test(mix_amount_weights_first),
        cmocka_unit_test(instances_placed),
        cmocka_unit_test(unused_parameters_warned),
        cmocka_unit_test(convert_round_trip),
        cmocka_unit_test(convert_refuses_non_utf8),
        cmocka_unit_test(cli_convert_and_render),
        cmocka_unit_test(convert_textures_round_trip),
        cmocka_unit_test(digest_of_bytes),
        cmocka_unit_test(media_mapped),
        cmocka_unit_test(shutter_swapped_warned),
    };
    return cmocka_run_group_tests(tests, ts_tmp_group_setup, ts_tmp_group_teardown);
}
