/* test_instance.c — object instancing (geometry/accel.h, scene_builder.h): an instanced
 * scene against the same geometry placed directly, ray by ray and image by image; rays
 * leaving one instance's triangle reaching another's copy of it; memory; refusals.
 *
 * Why "within float rounding" and not bit for bit: a directly placed mesh has its vertices
 * transformed to world space and rounded to float once by the builder, an instanced one
 * keeps its object-space floats and is intersected there (the world ray taken to object
 * space in double), so the two hit points are different roundings of the same exact point:
 * each within its own p_error of it, so within the sum of the two of each other, which is
 * what the ray comparison asserts (with normals and uvs to 2e-5). Analytic shapes compose
 * the same transforms in another association: a few 1e-16 relative apart. The images then
 * differ only where a sample's path reaches a discontinuity (an edge, a shadow boundary)
 * differently: the bounds are on the mean absolute difference relative to the mean (1e-5,
 * measured 6e-8) and on the fraction of pixels that differ by more than 1e-3 relative
 * (0.5%, measured none). The scenes have point lights only: an infinite light's power
 * depends on the scene's bounds, which for instances are their objects' boxes transformed
 * (looser than the direct shapes' own), and so would change the light-selection pmf and
 * with it the noise (not the expectation). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <malloc.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "film/film.h"
#include "camera/camera.h"
#include "geometry/accel.h"
#include "render/render.h"
#include "build/scene_builder.h"
#include "json/scene_json.h"

static ts_scene *load(const char *doc)
{
    ts_scene *s = NULL;
    ts_error err = {0};
    if (ts_scene_load_text(doc, strlen(doc), NULL, NULL, NULL, &s, &err)) fail_msg("%s", err.message);
    return s;
}

static void refused_json(const char *doc, const char *msg)
{
    ts_scene *s = NULL;
    ts_error err = {0};
    assert_int_not_equal(ts_scene_load_text(doc, strlen(doc), NULL, NULL, NULL, &s, &err), TS_OK);
    if (!strstr(err.message, msg)) fail_msg("got '%s', expected '%s'", err.message, msg);
}

#define HEAD                                                                                                        \
    "{\"tessera\": 1, \"camera\": {\"from\": [0.3, 2, 9], \"to\": [0, 0.2, 0], \"fov\": 40}, \"film\": {\"width\": " \
    "48, \"height\": 40}, \"sampler\": {\"spp\": 8}, \"integrator\": {\"type\": \"path\", \"max_depth\": 3}, "        \
    "\"materials\": {\"m\": {\"type\": \"diffuse\", \"reflectance\": [0.6, 0.5, 0.4]}, \"g\": {\"type\": "            \
    "\"plastic\"}}, "
#define LIGHTS                                                                                                      \
    "\"lights\": [{\"type\": \"point\", \"position\": [2, 5, 4], \"intensity\": [40, 40, 40]}, {\"type\": "          \
    "\"point\", \"position\": [-3, 2, 5], \"intensity\": [10, 10, 10]}]}"
/* The object's shapes, in its space: a mesh with normals and uvs under its own transform, a
 * sphere and a partial cylinder. */
#define MESH(T)                                                                                                     \
    "{\"type\": \"mesh\", \"material\": \"m\", " T "\"positions\": [-1,0,-1, 1,0,-1, 1,0,1, -1,0,1, 0,1.2,0], "       \
    "\"normals\": [-1,0.3,-1, 1,0.3,-1, 1,0.3,1, -1,0.3,1, 0,1,0], \"uvs\": [0,0, 1,0, 1,1, 0,1, 0.5,0.5], "         \
    "\"indices\": [0,1,4, 1,2,4, 2,3,4, 3,0,4, 0,2,1, 0,3,2]}"
#define SPHERE(T) "{\"type\": \"sphere\", \"material\": \"g\", " T "\"center\": [0, 1.6, 0], \"radius\": 0.4}"
#define TUBE(T)                                                                                                     \
    "{\"type\": \"cylinder\", \"material\": \"m\", " T "\"p0\": [1.3, 0, 0], \"p1\": [1.3, 0.8, 0], \"radius\": "    \
    "0.25, \"phi_max\": 250}"
#define OWN "{\"rotate\": {\"angle\": 15, \"axis\": [0, 1, 0]}}"
#define I1 "{\"translate\": [-1.8, 0, 0]}"
#define I2 "{\"scale\": 1.3}, {\"rotate\": {\"angle\": 50, \"axis\": [0, 1, 0.2]}}, {\"translate\": [1.5, 0, -0.5]}"
/* A non-uniform scale: instances interpolate the object's shading normals and then
 * transform them, direct meshes transform them and then interpolate; both keep the vertex
 * normals' lengths (as pbrt-v3), so both are linear and agree under any transform (with
 * the direct mesh's normals normalised after the transform they differed by 0.086 here). */
#define I4 "{\"scale\": [1.3, 0.7, 1]}, {\"rotate\": {\"angle\": 50, \"axis\": [0, 1, 0.2]}}, {\"translate\": [0, 0, -2.5]}"
#define I3 "{\"scale\": [1, 1, -1]}, {\"translate\": [0, 0, 2]}"

#define INST(I) ", {\"object\": \"thing\", \"transform\": [" I "]}"
#define DIRECT(I) ", " MESH("\"transform\": [" OWN ", " I "], ") ", " SPHERE("\"transform\": [" I "], ") ", " TUBE("\"transform\": [" I "], ")
#define INSTANCED_DOC(EXTRA)                                                                                         \
    HEAD "\"objects\": {\"thing\": {\"shapes\": [" MESH("\"transform\": [" OWN "], ") ", " SPHERE("") ", " TUBE("") "]}}, " \
         "\"instances\": [{\"object\": \"thing\", \"transform\": [" I1 "]}" INST(I2) INST(I3) EXTRA "], "              \
         "\"shapes\": [{\"type\": \"disk\", \"normal\": [0, 1, 0], \"radius\": 8, \"material\": \"m\"}], " LIGHTS
#define DIRECT_DOC(EXTRA)                                                                                            \
    HEAD "\"shapes\": [{\"type\": \"disk\", \"normal\": [0, 1, 0], \"radius\": 8, \"material\": \"m\"}" DIRECT(I1)      \
        DIRECT(I2) DIRECT(I3) EXTRA "], " LIGHTS

/* Similarity instances only (I1 to I3), and with the non-uniform I4. */
static const char *instanced_doc = INSTANCED_DOC(""), *direct_doc = DIRECT_DOC("");
static const char *instanced_aniso = INSTANCED_DOC(INST(I4)), *direct_aniso = DIRECT_DOC(DIRECT(I4));

static double vdiff(ts_vec3 a, ts_vec3 b) { return fmax(fabs(a.x - b.x), fmax(fabs(a.y - b.y), fabs(a.z - b.z))); }

/* Every camera ray (and a bounce off each hit) meets the same surface in both scenes. */
static void rays_match(const char *inst_doc, const char *dir_doc, uint32_t n_instances)
{
    ts_scene *a = load(inst_doc), *b = load(dir_doc);
    assert_int_equal(a->n_instances, n_instances);
    assert_int_equal(a->n_objects, 1);
    int hits = 0, inst_hits = 0;
    for (int y = 0; y < 120; y++)
        for (int x = 0; x < 144; x++) {
            ts_ray r = ts_camera_ray(&a->camera, (ts_vec2){(x + 0.5f) / 3, (y + 0.5f) / 3}, (ts_vec2){0.5f, 0.5f});
            for (int bounce = 0; bounce < 2; bounce++) {
                ts_interaction sa, sb;
                bool ha = ts_accel_intersect(a->accel, &r, &sa), hb = ts_accel_intersect(b->accel, &r, &sb);
                if (ha != hb) fail_msg("pixel %d,%d bounce %d: hit %d vs %d", x, y, bounce, ha, hb);
                if (!ha) break;
                hits++;
                inst_hits += sa.inst != 0;
                const ts_shape *ka = &a->shapes[sa.shape], *kb = &b->shapes[sb.shape];
                assert_int_equal(ka->type, kb->type);
                assert_int_equal(ka->material, kb->material);
                assert_int_equal(sa.prim, sb.prim);
                /* Each point is within its p_error of the exact hit on its own float triangle;
                 * the two triangles' vertices are roundings of the same exact ones (the direct
                 * mesh's once in world space, the object's once in its space), so their planes
                 * are a few ulps apart and the hit slides by that over the cosine. */
                double scale = fmax(fabs(sa.p.x), fmax(fabs(sa.p.y), fabs(sa.p.z))) + 2;
                double cos_t = fmax(fabs(ts_vec3_dot(sa.n, ts_vec3_normalize(r.d))), 0.05);
                double dp = vdiff(sa.p, sb.p), tol = fmax(sa.p_error.x, fmax(sa.p_error.y, sa.p_error.z)) +
                                                      fmax(sb.p_error.x, fmax(sb.p_error.y, sb.p_error.z)) +
                                                      0x1p-21 * scale / cos_t;
                if (!(dp <= tol))
                    fail_msg("pixel %d,%d bounce %d: points %g apart, error bounds %g (type %d, inst %u, prim %u, p %g %g %g)", x, y,
                             bounce, dp, tol, ka->type, sa.inst, sa.prim, sa.p.x, sa.p.y, sa.p.z);
                if (!(vdiff(sa.n, sb.n) < 2e-5 && vdiff(sa.ns, sb.ns) < 2e-5))
                    fail_msg("pixel %d,%d: normals differ (%g, %g)", x, y, vdiff(sa.n, sb.n), vdiff(sa.ns, sb.ns));
                if (!(fabsf(sa.uv.x - sb.uv.x) < 2e-5f && fabsf(sa.uv.y - sb.uv.y) < 2e-5f))
                    fail_msg("pixel %d,%d: uv differ", x, y);
                double du = vdiff(sa.dpdu, sb.dpdu), dv = vdiff(sa.dpdv, sb.dpdv);
                if (!(du < 1e-4 * (1 + ts_vec3_length(sb.dpdu)) && dv < 1e-4 * (1 + ts_vec3_length(sb.dpdv))))
                    fail_msg("pixel %d,%d: dp/du, dp/dv differ by %g, %g", x, y, du, dv);
                /* Bounce along the mirror direction from the instanced hit, offset by its own bound. */
                ts_vec3 d = ts_vec3_sub(r.d, ts_vec3_scale(sa.n, 2 * ts_vec3_dot(r.d, sa.n)));
                r = ts_spawn_ray(&sa, a->shapes, d);
            }
        }
    print_message("%d hits compared, %d through instances\n", hits, inst_hits);
    assert_true(inst_hits > 1000);
    ts_scene_destroy(a);
    ts_scene_destroy(b);
}

static void test_rays_match(void **state)
{
    (void)state;
    rays_match(instanced_doc, direct_doc, 3);
    rays_match(instanced_aniso, direct_aniso, 4);
}

static ts_film *render(const ts_scene *s)
{
    ts_error err = {0};
    ts_film *f = ts_film_create(s->width, s->height, 0, 0, s->width, s->height, &err);
    assert_non_null(f);
    ts_render_stats stats = {0};
    ts_render_request req = {s, s->integrator.type, f, 0, s->spp, 2, NULL, NULL, NULL};
    if (ts_render(&req, &stats, &err)) fail_msg("%s", err.message);
    assert_int_equal(stats.counters.nonfinite, 0);
    return f;
}

static void test_images_match(void **state)
{
    (void)state;
    ts_scene *a = load(instanced_doc), *b = load(direct_doc);
    ts_film *fa = render(a), *fb = render(b);
    double sum = 0, sum_diff = 0;
    int off = 0, n = a->width * a->height;
    for (int i = 0; i < n; i++) {
        ts_rgb pa = ts_film_pixel_rgb(fa, i % a->width, i / a->width), pb = ts_film_pixel_rgb(fb, i % a->width, i / a->width);
        double va = pa.r + pa.g + pa.b, vb = pb.r + pb.g + pb.b;
        sum += vb;
        sum_diff += fabs(va - vb);
        off += fabs(va - vb) > 1e-3 * fmax(vb, 1e-3);
    }
    print_message("mean |difference| / mean = %.3g, %d of %d pixels beyond 1e-3\n", sum_diff / sum, off, n);
    assert_true(sum_diff / sum < 1e-5);
    assert_true(off <= n / 200);
    ts_film_destroy(fa);
    ts_film_destroy(fb);
    ts_scene_destroy(a);
    ts_scene_destroy(b);
}

/* A ray leaving a triangle of one instance meets the same triangle of another instance:
 * the skip ids name the instance too. */
static void test_skip_is_per_instance(void **state)
{
    (void)state;
    const char *doc = "{\"tessera\": 1, \"camera\": {\"from\": [0, 0, 5], \"to\": [0, 0, 0]}, \"materials\": {\"m\": "
                      "{\"type\": \"diffuse\"}}, \"objects\": {\"q\": {\"shapes\": [{\"type\": \"mesh\", \"material\": "
                      "\"m\", \"positions\": [-1,-1,0, 1,-1,0, 1,1,0, -1,1,0], \"indices\": [0,1,2, 0,2,3]}]}}, "
                      "\"instances\": [{\"object\": \"q\"}, {\"object\": \"q\", \"transform\": [{\"translate\": [0, 0, "
                      "1]}]}]}";
    ts_scene *s = load(doc);
    ts_ray r = ts_ray_make((ts_vec3){0.3f, 0.2f, -2}, (ts_vec3){0, 0, 1}, INFINITY);
    ts_interaction h0, h1;
    assert_true(ts_accel_intersect(s->accel, &r, &h0));
    assert_int_equal(h0.inst, 1);
    assert_true(fabsf(h0.t - 2) < 1e-6f);
    ts_ray up = ts_spawn_ray(&h0, s->shapes, (ts_vec3){0, 0, 1});
    assert_int_equal(up.skip_inst, 1);
    assert_true(ts_accel_intersect(s->accel, &up, &h1));
    assert_int_equal(h1.inst, 2);
    assert_int_equal(h1.prim, h0.prim);
    assert_true(fabsf(h1.p.z - 1) < 1e-6f);
    assert_true(ts_accel_occluded(s->accel, &(ts_ray){up.o, up.d, 2, up.skip_shape, up.skip_prim, up.skip_inst}));
    ts_scene_destroy(s);
}

/* One object of 10k triangles, instanced once and 1000 times: the heap the built scenes
 * hold (glibc's count, Embree's buffers included). */
static size_t heap_now(void)
{
    struct mallinfo2 mi = mallinfo2();
    return mi.uordblks + mi.hblkhd;
}

static size_t scene_bytes(uint32_t n_instances)
{
    const int g = 71; /* 71 × 71 × 2 = 10082 triangles */
    float *p = malloc(sizeof *p * 3 * (g + 1) * (g + 1));
    uint32_t *ix = malloc(sizeof *ix * 6 * g * g);
    for (int j = 0; j <= g; j++)
        for (int i = 0; i <= g; i++) {
            float *q = p + 3 * (j * (g + 1) + i);
            q[0] = (float)i / g, q[1] = (float)j / g, q[2] = 0.05f * sinf(7.0f * i / g) * cosf(5.0f * j / g);
        }
    for (int j = 0, t = 0; j < g; j++)
        for (int i = 0; i < g; i++, t++) {
            uint32_t a = j * (g + 1) + i, b = a + 1, c = a + g + 2, d = a + g + 1;
            uint32_t tri[6] = {a, b, c, a, c, d};
            memcpy(ix + 6 * t, tri, sizeof tri);
        }
    size_t before = heap_now();
    ts_scene_builder *b;
    ts_error err = {0};
    assert_int_equal(ts_scene_builder_create(NULL, NULL, &b, &err), TS_OK);
    ts_film_desc film = {8, 8, {0, 1, 0, 1}, TS_FILTER_BOX, 0.5f};
    ts_camera_desc cam = {.type = TS_CAMERA_PERSPECTIVE, .from = {0, 0, 50}, .to = {0, 0, 0}, .up = {0, 1, 0}, .fov_deg = 40, .focus_distance = 1};
    ts_sampler smp = {.type = TS_SAMPLER_SOBOL};
    ts_integrator_desc in = {.type = TS_INTEGRATOR_NORMALS};
    ts_material m = {.type = TS_MATERIAL_DIFFUSE, .reflectance = {{0.5f, 0.5f, 0.5f}}};
    assert_int_equal(ts_scene_builder_add_material(b, "m", &m, NULL, &err), TS_OK);
    assert_int_equal(ts_scene_builder_set_film(b, &film, &err), TS_OK);
    assert_int_equal(ts_scene_builder_set_camera(b, &cam, &err), TS_OK);
    assert_int_equal(ts_scene_builder_set_sampler(b, &smp, 1, &err), TS_OK);
    assert_int_equal(ts_scene_builder_set_integrator(b, &in, &err), TS_OK);
    assert_int_equal(ts_scene_builder_set_digest(b, "0000000000000000000000000000000000000000000000000000000000000000", &err), TS_OK);
    uint32_t obj;
    assert_int_equal(ts_scene_builder_begin_object(b, "grid", &obj, &err), TS_OK);
    ts_shape_desc d = {.type = TS_SHAPE_MESH, .to_world = ts_xform_identity(),
                       .mesh = {(uint32_t)((g + 1) * (g + 1)), (uint32_t)(2 * g * g), p, NULL, NULL, ix}};
    assert_int_equal(ts_scene_builder_add_shape(b, &d, NULL, &err), TS_OK);
    assert_int_equal(ts_scene_builder_end_object(b, &err), TS_OK);
    for (uint32_t k = 0; k < n_instances; k++) {
        ts_xform x = ts_xform_translate((ts_dvec3){(double)(k % 40) * 1.1, (double)(k / 40) * 1.1, 0});
        assert_int_equal(ts_scene_builder_add_instance(b, obj, &x, &err), TS_OK);
    }
    ts_scene *s;
    if (ts_scene_builder_finish(b, &s, &err)) fail_msg("%s", err.message);
    ts_scene_builder_destroy(b);
    free(p), free(ix);
    size_t bytes = heap_now() - before;
    /* It renders: the camera sees instances across the grid of 40 × 25. */
    ts_ray r = ts_ray_make((ts_vec3){20.5f, 13.3f, 5}, (ts_vec3){0, 0, -1}, INFINITY);
    ts_interaction si;
    assert_int_equal(ts_accel_intersect(s->accel, &r, &si), n_instances == 1000);
    ts_scene_destroy(s);
    return bytes;
}

static void test_memory(void **state)
{
    (void)state;
    size_t one = scene_bytes(1), many = scene_bytes(1000);
    print_message("10082-triangle object: 1 instance %.2f MB, 1000 instances %.2f MB (%.2f×)\n", one / 1e6, many / 1e6,
                  (double)many / one);
    /* The object once, plus per instance Embree's instance geometry and its share of the
     * top-level BVH (measured 1.2 kB an instance, 1.82× in all): bounded by 2 kB an
     * instance. 1000 copies of the geometry would be 1000×. */
    assert_true(many < one + 1000 * 2048);
}

static void test_refusals(void **state)
{
    (void)state;
    ts_scene_builder *b;
    ts_error err = {0};
    assert_int_equal(ts_scene_builder_create(NULL, NULL, &b, &err), TS_OK);
    ts_material m = {.type = TS_MATERIAL_DIFFUSE, .reflectance = {{0.5f, 0.5f, 0.5f}}};
    assert_int_equal(ts_scene_builder_add_material(b, "m", &m, NULL, &err), TS_OK);
    assert_int_not_equal(ts_scene_builder_end_object(b, &err), TS_OK);
    assert_string_equal(err.message, "no object is being defined");
    uint32_t id;
    assert_int_equal(ts_scene_builder_begin_object(b, "a", &id, &err), TS_OK);
    assert_int_not_equal(ts_scene_builder_begin_object(b, "b", NULL, &err), TS_OK);
    assert_string_equal(err.message, "object \"b\" begins inside object \"a\": objects do not nest (nor do they in pbrt-v3)");
    ts_xform x = ts_xform_identity();
    assert_int_not_equal(ts_scene_builder_add_instance(b, id, &x, &err), TS_OK);
    assert_string_equal(err.message, "an instance inside object \"a\": instances do not nest (nor do they in pbrt-v3)");
    ts_shape_desc lamp = {.type = TS_SHAPE_SPHERE, .to_world = x, .sphere = {1}, .emission = {1, 1, 1}};
    assert_int_equal(ts_scene_builder_add_shape(b, &lamp, NULL, &err), TS_ERR_UNSUPPORTED);
    assert_true(strstr(err.message, "a shape of an object cannot emit") != NULL);
    assert_int_equal(ts_scene_builder_end_object(b, &err), TS_OK);
    assert_int_not_equal(ts_scene_builder_begin_object(b, "a", NULL, &err), TS_OK);
    assert_string_equal(err.message, "object \"a\" is defined twice");
    ts_xform singular = ts_xform_scale((ts_dvec3){1, 0, 1});
    assert_int_not_equal(ts_scene_builder_add_instance(b, id, &singular, &err), TS_OK);
    assert_int_not_equal(ts_scene_builder_add_instance(b, 5, &x, &err), TS_OK);
    assert_string_equal(err.message, "object: no object of id 5 (1 were defined)");
    ts_scene_builder_destroy(b);

    refused_json("{\"tessera\": 1, \"camera\": {\"from\": [0, 0, 5], \"to\": [0, 0, 0]}, \"materials\": {\"m\": {\"type\": "
                 "\"diffuse\"}}, \"instances\": [{\"object\": \"nope\"}]}",
                 "instances[0].object: no object named \"nope\" in 'objects'");
    refused_json("{\"tessera\": 1, \"camera\": {\"from\": [0, 0, 5], \"to\": [0, 0, 0]}, \"materials\": {\"m\": {\"type\": "
                 "\"diffuse\"}}, \"objects\": {\"o\": {\"shapes\": [{\"type\": \"sphere\", \"radius\": 1, \"material\": "
                 "\"m\", \"emission\": 1}]}}}",
                 "objects.o.shapes[0]: a shape of an object cannot emit");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rays_match),  cmocka_unit_test(test_images_match), cmocka_unit_test(test_skip_is_per_instance),
        cmocka_unit_test(test_memory),      cmocka_unit_test(test_refusals),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
