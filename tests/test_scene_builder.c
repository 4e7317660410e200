/* test_scene_builder.c — the scene builder (scene_builder.h) driven directly, as a second
 * front end would: a scene built call by call equals the same scene loaded from JSON, bit
 * for bit; every check the builder makes refuses a bad value with its sentence, adds
 * nothing and leaves the builder usable; the area lights, the mirrored-mesh winding, the
 * limits and the end of the builder's life behave as the header says. (The JSON front end
 * checks its documents before the builder sees them, so these checks cannot be reached
 * from JSON: this test is what exercises them.) */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>

#include <cmocka.h>

#include <math.h>
#include <string.h>

#include "integrators/effects.h"
#include "build/scene_builder.h"
#include "json/scene_json.h"

static const char digest[] = "00112233445566778899aabbccddeeff00112233445566778899aabbccddeeff";

static void ok(ts_status st, const ts_error *err)
{
    if (st) fail_msg("unexpected failure: %s", err->message);
}

/* A builder with film, camera, sampler, integrator and digest set, and material "m". */
static ts_scene_builder *base(const ts_scene_limits *lim)
{
    ts_scene_builder *b = NULL;
    ts_error err = {0};
    ok(ts_scene_builder_create(lim, NULL, &b, &err), &err);
    ts_film_desc film = {64, 48, {0, 1, 0, 1}, TS_FILTER_GAUSSIAN, 1.5f};
    ok(ts_scene_builder_set_film(b, &film, &err), &err);
    ts_camera_desc cam = {TS_CAMERA_PERSPECTIVE, {0, 1, 6}, {0, 0, 0}, {0, 1, 0}, 40, 1, 0, 1};
    ok(ts_scene_builder_set_camera(b, &cam, &err), &err);
    ts_sampler smp = {TS_SAMPLER_SOBOL, 3};
    ok(ts_scene_builder_set_sampler(b, &smp, 4, &err), &err);
    ts_integrator_desc in = {.type = TS_INTEGRATOR_PATH,
                             .max_depth = 5,
                             .rr_depth = 3,
                             .light_sampling = TS_LIGHT_SELECT_POWER,
                             .samples_per_light = 1,
                             .ao_distance = INFINITY};
    ok(ts_scene_builder_set_integrator(b, &in, &err), &err);
    ok(ts_scene_builder_set_digest(b, digest, &err), &err);
    ts_material m = {.type = TS_MATERIAL_DIFFUSE, .reflectance = {{0.5f, 0.5f, 0.5f}}};
    uint32_t id = 7;
    ok(ts_scene_builder_add_material(b, "m", &m, &id, &err), &err);
    assert_int_equal(id, 0);
    return b;
}

static const float quad_p[] = {-1, 0, -1, 1, 0, -1, 1, 0, 1, -1, 0, 1};
static const uint32_t quad_i[] = {0, 2, 1, 0, 3, 2};

static ts_shape_desc quad(void)
{
    ts_shape_desc d = {.type = TS_SHAPE_MESH, .material = 0, .to_world = ts_xform_identity()};
    d.mesh = (ts_mesh){4, 2, quad_p, NULL, NULL, quad_i};
    return d;
}

static ts_shape_desc sphere(double r)
{
    ts_shape_desc d = {.type = TS_SHAPE_SPHERE, .material = 0, .to_world = ts_xform_identity()};
    d.sphere.radius = r;
    return d;
}

#define SAME(field) (memcmp(&a->field, &b->field, sizeof a->field) == 0)
static bool same_material(const ts_material *a, const ts_material *b)
{
    return SAME(type) && SAME(reflectance) && SAME(transmittance) && SAME(sigma_deg) && SAME(eta) &&
           SAME(conductor_eta) && SAME(conductor_k) && SAME(roughness) && SAME(distribution) &&
           SAME(diffuse) && SAME(specular) && a->fourier == b->fourier;
}
#undef SAME

/* The same scene twice: from JSON, and from builder calls that do what the JSON front end
 * is documented to do with it. Every field the renderer reads must come out identical. */
static void test_same_scene_as_json(void **state)
{
    (void)state;
    const char *doc =
        "{\"tessera\":1,\"name\":\"twin\",\"camera\":{\"from\":[0,1,6],\"to\":[0,0,0],\"fov\":40},"
        "\"film\":{\"width\":64,\"height\":48,\"crop\":[0.25,0.75,0,0.5],\"filter\":{\"type\":\"mitchell\"}},"
        "\"sampler\":{\"spp\":4,\"seed\":3},\"integrator\":{\"type\":\"path\",\"light_sampling\":\"uniform\"}"
        ","
        "\"materials\":{\"m\":{\"type\":\"diffuse\"},\"g\":{\"type\":\"conductor\",\"eta\":[0.2,0.4,1.4],"
        "\"k\":[3.6,2.4,1.8],\"roughness\":0.2}},"
        "\"shapes\":[{\"type\":\"sphere\",\"center\":[1,0.5,0],\"radius\":0.5,\"material\":\"g\"},"
        "{\"type\":\"mesh\",\"positions\":[-1,0,-1,1,0,-1,1,0,1,-1,0,1],\"indices\":[0,2,1,0,3,2],"
        "\"material\":\"m\",\"emission\":[2,2,2],\"transform\":[{\"scale\":[-1,1,1]},{\"translate\":[0,2,0]}]"
        "}],"
        "\"lights\":[{\"type\":\"spot\",\"from\":[0,4,0],\"to\":[0,0,0],\"intensity\":10,\"cone_angle\":30,"
        "\"cone_delta\":5}]}";
    ts_scene *js = NULL;
    ts_error err = {0};
    ok(ts_scene_load_text(doc, strlen(doc), NULL, "t", NULL, &js, &err), &err);

    ts_scene_builder *b = NULL;
    ok(ts_scene_builder_create(NULL, NULL, &b, &err), &err);
    ok(ts_scene_builder_set_name(b, "twin", &err), &err);
    ok(ts_scene_builder_set_digest(b, js->digest, &err), &err);
    ts_film_desc film = {64, 48, {0.25f, 0.75f, 0, 0.5f}, TS_FILTER_MITCHELL, 2.0f};
    ok(ts_scene_builder_set_film(b, &film, &err), &err);
    ts_camera_desc cam = {TS_CAMERA_PERSPECTIVE, {0, 1, 6}, {0, 0, 0}, {0, 1, 0}, 40, 1, 0, 1};
    cam.shutter_close = 1; /* the JSON front end's default shutter [0, 1] */
    ok(ts_scene_builder_set_camera(b, &cam, &err), &err);
    ts_sampler smp = {TS_SAMPLER_SOBOL, 3};
    ok(ts_scene_builder_set_sampler(b, &smp, 4, &err), &err);
    ts_integrator_desc in = {.type = TS_INTEGRATOR_PATH,
                             .max_depth = 5,
                             .rr_depth = 3,
                             .light_sampling = TS_LIGHT_SELECT_UNIFORM,
                             .samples_per_light = 1,
                             .ao_distance = INFINITY};
    ok(ts_scene_builder_set_integrator(b, &in, &err), &err);
    /* The JSON front end fills the parameters of the type's description
     * (materials/material_desc.h) and leaves every other field zero. */
    ts_material m = {.type = TS_MATERIAL_DIFFUSE, .reflectance = ts_material_rgb_gray(0.5f)};
    ts_material g = {.type = TS_MATERIAL_CONDUCTOR,
                     .conductor_eta = {{0.2f, 0.4f, 1.4f}},
                     .conductor_k = {{3.6f, 2.4f, 1.8f}},
                     .roughness = {0.2f}};
    uint32_t mid, gid;
    ok(ts_scene_builder_add_material(b, "m", &m, &mid, &err), &err);
    ok(ts_scene_builder_add_material(b, "g", &g, &gid, &err), &err);
    /* The JSON front end composes the transform list (here none) with the placement. */
    ts_shape_desc s0 = sphere(0.5);
    s0.material = gid;
    ts_xform none = ts_xform_identity(), at = ts_xform_translate((ts_dvec3){1, 0.5, 0});
    s0.to_world = ts_xform_compose(&none, &at);
    ok(ts_scene_builder_add_shape(b, &s0, NULL, &err), &err);
    ts_shape_desc s1 = quad();
    s1.material = mid;
    s1.emission = ts_rgb_gray(2);
    ts_xform mirror = ts_xform_scale((ts_dvec3){-1, 1, 1}), up = ts_xform_translate((ts_dvec3){0, 2, 0});
    s1.to_world = ts_xform_compose(&mirror, &none); /* the list, applied first to last */
    s1.to_world = ts_xform_compose(&up, &s1.to_world);
    ok(ts_scene_builder_add_shape(b, &s1, NULL, &err), &err);
    ts_light_desc spot = {.type = TS_LIGHT_SPOT,
                          .color = ts_rgb_gray(10),
                          .from = {0, 4, 0},
                          .to = {0, 0, 0},
                          .cone_angle_deg = 30,
                          .cone_delta_deg = 5,
                          .to_world = ts_xform_identity()};
    ok(ts_scene_builder_add_light(b, &spot, &err), &err);
    ts_scene *bs = NULL;
    ok(ts_scene_builder_finish(b, &bs, &err), &err);
    ts_scene_builder_destroy(b);

    assert_string_equal(bs->name, js->name);
    assert_string_equal(bs->digest, js->digest);
    assert_memory_equal(&bs->camera, &js->camera, sizeof bs->camera);
    assert_int_equal(bs->crop_x0, js->crop_x0);
    assert_int_equal(bs->crop_x1, js->crop_x1);
    assert_int_equal(bs->crop_y0, js->crop_y0);
    assert_int_equal(bs->crop_y1, js->crop_y1);
    assert_memory_equal(&bs->filter, &js->filter, sizeof bs->filter);
    assert_int_equal(bs->n_materials, 2);
    for (uint32_t i = 0; i < 2; i++)
        assert_true(same_material(&bs->materials[i], &js->materials[i]));
    assert_int_equal(bs->n_shapes, js->n_shapes);
    for (uint32_t i = 0; i < bs->n_shapes; i++) {
        const ts_shape *x = &bs->shapes[i], *y = &js->shapes[i];
        assert_int_equal(x->type, y->type);
        assert_int_equal(x->material, y->material);
        assert_int_equal(x->first_light, y->first_light);
        assert_int_equal(x->reverse_orientation, y->reverse_orientation);
        assert_int_equal(x->partial, y->partial);
        assert_memory_equal(&x->to_world, &y->to_world, sizeof x->to_world);
    }
    assert_memory_equal(&bs->shapes[0].sphere, &js->shapes[0].sphere, sizeof bs->shapes[0].sphere);
    assert_memory_equal(bs->shapes[1].mesh.p, js->shapes[1].mesh.p, 12 * sizeof(float));
    assert_memory_equal(bs->shapes[1].mesh.index, js->shapes[1].mesh.index, 6 * sizeof(uint32_t));
    /* One spot, then the emitting rectangle (its two triangles are one light). */
    assert_int_equal(bs->n_lights, 2);
    assert_int_equal(js->n_lights, 2);
    assert_true(bs->lights[1].rect && js->lights[1].rect && bs->lights[1].prim_b == js->lights[1].prim_b);
    for (uint32_t i = 0; i < 2; i++) {
        const ts_light *x = &bs->lights[i], *y = &js->lights[i];
        assert_int_equal(x->type, y->type);
        assert_memory_equal(&x->color, &y->color, sizeof x->color);
        assert_memory_equal(&x->position, &y->position, sizeof x->position);
        assert_memory_equal(&x->direction, &y->direction, sizeof x->direction);
        assert_true(x->cos_total == y->cos_total && x->cos_falloff_start == y->cos_falloff_start);
        assert_int_equal(x->shape, y->shape);
        assert_int_equal(x->prim, y->prim);
        assert_true(x->geom.area == y->geom.area && x->geom.similarity == y->geom.similarity &&
                    x->geom.radius == y->geom.radius && x->geom.det_abs == y->geom.det_abs &&
                    x->geom.triangle_mode == y->geom.triangle_mode);
    }
    assert_int_equal(bs->lights[1].type, TS_LIGHT_AREA);
    assert_int_equal(bs->shapes[1].first_light, 1);
    assert_int_equal(bs->light_distribution.n, 2);
    assert_memory_equal(bs->light_distribution.table.pmf, js->light_distribution.table.pmf,
                        2 * sizeof(float));
    assert_int_equal(bs->effects, js->effects);
    assert_memory_equal(&bs->bounds, &js->bounds, sizeof bs->bounds);
    ts_scene_destroy(bs);
    ts_scene_destroy(js);
}

/* A mirroring transform reverses the winding: the triangle keeps facing +y (as in object
 * space), and the normals go through the inverse transpose keeping their lengths (which
 * weight their interpolation, as in pbrt-v3): y scaled by 4 divides them by 4, exactly. */
static void test_mesh_to_world(void **state)
{
    (void)state;
    ts_scene_builder *b = base(NULL);
    ts_error err = {0};
    static const float n[] = {0, 2, 0, 0, 3, 0, 0, 1, 0, 0, 0.5f, 0};
    ts_shape_desc d = quad();
    d.mesh.n = n;
    d.to_world = ts_xform_scale((ts_dvec3){1, 4, -2});
    uint32_t id = 9;
    ok(ts_scene_builder_add_shape(b, &d, &id, &err), &err);
    assert_int_equal(id, 0);
    ts_scene *s = NULL;
    ok(ts_scene_builder_finish(b, &s, &err), &err);
    ts_scene_builder_destroy(b);
    const ts_mesh *m = &s->shapes[0].mesh;
    assert_true(m != NULL && m->n != NULL);
    ts_vec3 p[3];
    for (int k = 0; k < 3; k++) {
        uint32_t i = m->index[k];
        p[k] = (ts_vec3){m->p[3 * i], m->p[3 * i + 1], m->p[3 * i + 2]};
    }
    /* object space: (p1 − p0) × (p2 − p0) of triangle 0, 2, 1 points along +y */
    ts_vec3 f = ts_vec3_cross(ts_vec3_sub(p[1], p[0]), ts_vec3_sub(p[2], p[0]));
    assert_true(f.y > 0);
    for (uint32_t v = 0; v < 4; v++) {
        assert_float_equal(m->n[3 * v], 0, 0);
        assert_float_equal(m->n[3 * v + 1], n[3 * v + 1] / 4, 0);
        assert_float_equal(m->n[3 * v + 2], 0, 0);
    }
    assert_float_equal(m->p[2], 2, 0); /* z = −1 scaled by −2 */
    ts_scene_destroy(s);
}

typedef struct expect {
    ts_status st;
    const char *text;
} expect;

static void refused(ts_status st, const ts_error *err, expect e)
{
    if (st == TS_OK) fail_msg("accepted, but should have been refused with \"%s\"", e.text);
    if (st != e.st)
        fail_msg("status %s (%s), expected %s", ts_status_name(st), err->message, ts_status_name(e.st));
    if (!strstr(err->message, e.text))
        fail_msg("message \"%s\" does not contain \"%s\"", err->message, e.text);
}

static void test_settings_refused(void **state)
{
    (void)state;
    ts_scene_limits lim;
    ts_scene_limits_default(&lim);
    lim.max_pixels = 4000;
    lim.max_spp = 64;
    ts_scene_builder *b = base(&lim);
    ts_error err = {0};
    struct {
        ts_film_desc film;
        expect e;
    } films[] = {
        {{0, 10, {0, 1, 0, 1}, TS_FILTER_BOX, 0.5f}, {TS_ERR_LIMIT, "film: 0 × 10 pixels"}},
        {{80, 80, {0, 1, 0, 1}, TS_FILTER_BOX, 0.5f},
         {TS_ERR_LIMIT, "80 × 80 pixels is more than the limit of 4000"}},
        {{10, 10, {0, 1, 0, 1}, TS_FILTER_BOX, 17},
         {TS_ERR_INVALID, "film.filter.radius: expected at most 16"}},
        {{10, 10, {0, 1, 0, 1}, TS_FILTER_BOX, 0},
         {TS_ERR_INVALID, "filter radius: expected a positive number"}},
        {{10, 10, {0, 1, 0, 1}, (ts_filter_type)9, 1}, {TS_ERR_INVALID, "filter type: unknown type 9"}},
        {{10, 10, {0.5f, 0.5f, 0, 1}, TS_FILTER_BOX, 1},
         {TS_ERR_INVALID, "film.crop: expected [x0, x1, y0, y1]"}},
        {{10, 10, {0.11f, 0.12f, 0, 1}, TS_FILTER_BOX, 1},
         {TS_ERR_INVALID, "film.crop: the window holds no pixel"}},
    };
    for (size_t i = 0; i < sizeof films / sizeof *films; i++)
        refused(ts_scene_builder_set_film(b, &films[i].film, &err), &err, films[i].e);

    struct {
        ts_camera_desc cam;
        expect e;
    } cams[] = {
        {{TS_CAMERA_PERSPECTIVE, {0, 0, 1}, {0, 0, 1}, {0, 1, 0}, 40, 1, 0, 1},
         {TS_ERR_INVALID, "camera: 'from' and 'to' are the same point"}},
        {{TS_CAMERA_PERSPECTIVE, {0, 0, 1}, {0, 0, 0}, {0, 0, 1}, 40, 1, 0, 1},
         {TS_ERR_INVALID, "camera.up: must not be parallel"}},
        {{TS_CAMERA_PERSPECTIVE, {0, 0, 1}, {0, 0, 0}, {0, 1, 0}, 180, 1, 0, 1},
         {TS_ERR_INVALID, "camera.fov"}},
        {{TS_CAMERA_PERSPECTIVE, {0, 0, 1}, {0, 0, 0}, {0, 1, 0}, 40, 1, -1, 1},
         {TS_ERR_INVALID, "camera.lens_radius: expected a finite number ≥ 0, got -1"}},
        {{TS_CAMERA_PERSPECTIVE, {0, 0, 1}, {0, 0, 0}, {0, 1, 0}, 40, 1, INFINITY, 1},
         {TS_ERR_INVALID, "camera.lens_radius"}},
        {{TS_CAMERA_PERSPECTIVE, {0, 0, 1}, {0, 0, 0}, {0, 1, 0}, 40, 1, 0.1f, 0},
         {TS_ERR_INVALID, "camera.focus_distance: expected a finite number > 0, got 0"}},
        {{TS_CAMERA_ORTHOGRAPHIC, {0, 0, 1}, {0, 0, 0}, {0, 1, 0}, 40, 0, 0, 1},
         {TS_ERR_INVALID, "camera.height"}},
        {{(ts_camera_type)5, {0, 0, 1}, {0, 0, 0}, {0, 1, 0}, 40, 1, 0, 1}, {TS_ERR_INVALID, "camera.type"}},
    };
    for (size_t i = 0; i < sizeof cams / sizeof *cams; i++)
        refused(ts_scene_builder_set_camera(b, &cams[i].cam, &err), &err, cams[i].e);

    ts_sampler smp = {TS_SAMPLER_INDEPENDENT, 0};
    refused(ts_scene_builder_set_sampler(b, &smp, 0, &err), &err, (expect){TS_ERR_INVALID, "sampler.spp"});
    refused(ts_scene_builder_set_sampler(b, &smp, 65, &err), &err,
            (expect){TS_ERR_INVALID, "expected 1 to 64 samples per pixel, got 65"});
    smp.type = (ts_sampler_type)4;
    refused(ts_scene_builder_set_sampler(b, &smp, 1, &err), &err, (expect){TS_ERR_INVALID, "sampler.type"});

    ts_integrator_desc path = {
        .type = TS_INTEGRATOR_PATH, .max_depth = -1, .light_sampling = TS_LIGHT_SELECT_POWER};
    refused(ts_scene_builder_set_integrator(b, &path, &err), &err,
            (expect){TS_ERR_INVALID, "integrator.max_depth: expected an integer in [0, 65535], got -1"});
    path.max_depth = 3, path.light_sampling = (ts_light_selection)(TS_LIGHT_SELECT_AUTO + 1);
    refused(ts_scene_builder_set_integrator(b, &path, &err), &err,
            (expect){TS_ERR_INVALID, "integrator.light_sampling"});
    ts_integrator_desc direct = {.type = TS_INTEGRATOR_DIRECT, .max_depth = 1001, .samples_per_light = 1};
    refused(ts_scene_builder_set_integrator(b, &direct, &err), &err, (expect){TS_ERR_INVALID, "[0, 1000]"});
    direct.max_depth = 2, direct.samples_per_light = 0;
    refused(ts_scene_builder_set_integrator(b, &direct, &err), &err,
            (expect){TS_ERR_INVALID, "samples_per_light"});
    ts_integrator_desc ao = {.type = TS_INTEGRATOR_AO, .ao_distance = 0};
    refused(ts_scene_builder_set_integrator(b, &ao, &err), &err,
            (expect){TS_ERR_INVALID, "integrator.max_distance"});
    ao.type = (ts_integrator_type)8;
    refused(ts_scene_builder_set_integrator(b, &ao, &err), &err, (expect){TS_ERR_INVALID, "integrator.type"});

    ts_job_desc job = {.effects_off = TS_EFFECT_DIFFUSE};
    refused(ts_scene_builder_set_job(b, &job, &err), &err,
            (expect){TS_ERR_INVALID, "only 'indirect' and 'depth_of_field' can be switched off"});
    job = (ts_job_desc){.spp = 65};
    refused(ts_scene_builder_set_job(b, &job, &err), &err, (expect){TS_ERR_INVALID, "job.spp"});
    job = (ts_job_desc){.time_limit_s = -1};
    refused(ts_scene_builder_set_job(b, &job, &err), &err, (expect){TS_ERR_INVALID, "job.time_limit_s"});
    job = (ts_job_desc){.target_error = NAN};
    refused(ts_scene_builder_set_job(b, &job, &err), &err, (expect){TS_ERR_INVALID, "job.target_error"});
    job = (ts_job_desc){.priority = 2000000};
    refused(ts_scene_builder_set_job(b, &job, &err), &err, (expect){TS_ERR_INVALID, "job.priority"});

    refused(ts_scene_builder_set_digest(b, "00ff", &err), &err,
            (expect){TS_ERR_INVALID, "digest: expected 64"});
    refused(ts_scene_builder_set_digest(b, "00112233445566778899AABBCCDDEEFF00112233445566778899AABBCCDDEEFF",
                                        &err),
            &err, (expect){TS_ERR_INVALID, "lower-case hex"});
    refused(ts_scene_builder_set_name(b, NULL, &err), &err, (expect){TS_ERR_INVALID, "name"});

    /* The settings base() made survive every refusal above. */
    ts_scene *s = NULL;
    ok(ts_scene_builder_finish(b, &s, &err), &err);
    assert_int_equal(s->width, 64);
    assert_int_equal(s->spp, 4);
    assert_int_equal(s->sampler.seed, 3);
    assert_int_equal(s->integrator.max_depth, 5);
    assert_string_equal(s->digest, digest);
    assert_string_equal(s->name, "untitled");
    ts_scene_destroy(s);
    ts_scene_builder_destroy(b);
}

static void test_elements_refused(void **state)
{
    (void)state;
    ts_scene_limits lim;
    ts_scene_limits_default(&lim);
    lim.max_triangles = 1;
    ts_scene_builder *b = base(&lim);
    ts_error err = {0};

    struct {
        ts_material m;
        expect e;
    } mats[] = {
        {{.type = TS_MATERIAL_DIFFUSE, .reflectance = {{0.5f, 1.5f, 0}}},
         {TS_ERR_INVALID, "reflectance: expected RGB in [0, 1], got (0.5, 1.5, 0)"}},
        {{.type = TS_MATERIAL_DIFFUSE, .sigma_deg = {91}},
         {TS_ERR_INVALID, "sigma: expected an angle in [0, 90]"}},
        {{.type = TS_MATERIAL_MIRROR, .reflectance = {{NAN, 0, 0}}}, {TS_ERR_INVALID, "reflectance"}},
        {{.type = TS_MATERIAL_DIELECTRIC, .eta = {0}},
         {TS_ERR_INVALID, "eta: expected a finite number > 0, got 0"}},
        {{.type = TS_MATERIAL_DIELECTRIC, .eta = {1.5f}, .transmittance = {{2, 0, 0}}},
         {TS_ERR_INVALID, "transmittance: expected RGB in [0, 1], got (2, 0, 0)"}},
        {{.type = TS_MATERIAL_CONDUCTOR, .conductor_k = {{INFINITY, 0, 0}}},
         {TS_ERR_INVALID, "k: expected finite RGB ≥ 0, got (inf, 0, 0)"}},
        {{.type = TS_MATERIAL_CONDUCTOR, .distribution = (ts_microfacet_type)4},
         {TS_ERR_INVALID, "distribution"}},
        {{.type = TS_MATERIAL_PLASTIC, .roughness = {-0.5f}},
         {TS_ERR_INVALID, "roughness: expected a finite number"}},
        {{.type = TS_MATERIAL_SUBSTRATE, .specular = {{0, 3, 0}}},
         {TS_ERR_INVALID, "specular: expected RGB in [0, 1], got (0, 3, 0)"}},
        {{.type = TS_MATERIAL_FOURIER},
         {TS_ERR_INVALID, "the Fourier table was not loaded by this scene builder"}},
        {{.type = (ts_material_type)20}, {TS_ERR_INVALID, "type: unknown material type 20"}},
    };
    for (size_t i = 0; i < sizeof mats / sizeof *mats; i++)
        refused(ts_scene_builder_add_material(b, "x", &mats[i].m, NULL, &err), &err, mats[i].e);
    ts_material fine = {.type = TS_MATERIAL_DIFFUSE};
    refused(ts_scene_builder_add_material(b, "m", &fine, NULL, &err), &err,
            (expect){TS_ERR_INVALID, "a material named \"m\" was added before"});
    assert_int_equal(ts_scene_builder_find_material(b, "x"), TS_NONE);
    uint32_t anon = 0;
    ok(ts_scene_builder_add_material(b, NULL, &fine, &anon, &err), &err); /* anonymous */
    assert_int_equal(anon, 1);
    assert_int_equal(ts_scene_builder_find_material(b, NULL), TS_NONE); /* no name finds it */
    assert_int_equal(ts_scene_builder_find_material(b, "m"), 0);

    static const float nan_p[] = {0, 0, 0, 1, 0, 0, 0, NAN, 0};
    static const float zero_n[] = {0, 1, 0, 0, 0, 0, 0, 1, 0};
    static const float inf_uv[] = {0, 0, 1, 0, INFINITY, 1};
    static const uint32_t tri[] = {0, 1, 2}, bad_tri[] = {0, 1, 3};
    static const float tri_p[] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    ts_shape_desc d = sphere(1);
    d.material = 2;
    refused(ts_scene_builder_add_shape(b, &d, NULL, &err), &err,
            (expect){TS_ERR_INVALID, "material: no material of id 2 (2 were added)"});
    d = sphere(1);
    d.emission = (ts_rgb){1, -1, 1};
    refused(ts_scene_builder_add_shape(b, &d, NULL, &err), &err,
            (expect){TS_ERR_INVALID, "emission: expected RGB ≥ 0, got (1, -1, 1)"});
    d = sphere(0);
    refused(ts_scene_builder_add_shape(b, &d, NULL, &err), &err,
            (expect){TS_ERR_INVALID, "radius: expected a positive number, got 0"});
    d = (ts_shape_desc){.type = TS_SHAPE_DISK, .to_world = ts_xform_identity(), .disk = {1, 1}};
    refused(ts_scene_builder_add_shape(b, &d, NULL, &err), &err,
            (expect){TS_ERR_INVALID, "inner_radius: expected a number in [0, radius), got 1"});
    d = (ts_shape_desc){.type = TS_SHAPE_CYLINDER, .to_world = ts_xform_identity(), .cylinder = {1, 0}};
    refused(ts_scene_builder_add_shape(b, &d, NULL, &err), &err,
            (expect){TS_ERR_INVALID, "height: expected a positive number, got 0"});
    d = (ts_shape_desc){.type = (ts_shape_type)9, .to_world = ts_xform_identity()};
    refused(ts_scene_builder_add_shape(b, &d, NULL, &err), &err,
            (expect){TS_ERR_INVALID, "unknown shape type 9"});
    d = quad();
    d.mesh.n_triangles = 0;
    refused(ts_scene_builder_add_shape(b, &d, NULL, &err), &err,
            (expect){TS_ERR_INVALID, "a mesh needs vertices and triangles (got 4 and 0)"});
    d = quad(); /* two triangles, one allowed */
    refused(ts_scene_builder_add_shape(b, &d, NULL, &err), &err,
            (expect){TS_ERR_LIMIT, "the scene's triangles exceed the limit of 1"});
    d.mesh = (ts_mesh){3, 1, nan_p, NULL, NULL, tri};
    refused(ts_scene_builder_add_shape(b, &d, NULL, &err), &err,
            (expect){TS_ERR_INVALID, "positions[7]: expected a finite number"});
    d.mesh = (ts_mesh){3, 1, tri_p, NULL, NULL, bad_tri};
    refused(ts_scene_builder_add_shape(b, &d, NULL, &err), &err,
            (expect){TS_ERR_INVALID, "indices[2]: 3 is not a vertex index (3 vertices)"});
    d.mesh = (ts_mesh){3, 1, tri_p, zero_n, NULL, tri};
    refused(ts_scene_builder_add_shape(b, &d, NULL, &err), &err,
            (expect){TS_ERR_INVALID, "normals[1]: expected a finite, non-zero normal"});
    d.mesh = (ts_mesh){3, 1, tri_p, NULL, inf_uv, tri};
    refused(ts_scene_builder_add_shape(b, &d, NULL, &err), &err,
            (expect){TS_ERR_INVALID, "uvs[4]: expected a finite number"});
    d.mesh = (ts_mesh){3, 1, tri_p, NULL, NULL, tri};
    d.to_world = ts_xform_scale((ts_dvec3){1e39, 1e39, 1e39});
    refused(ts_scene_builder_add_shape(b, &d, NULL, &err), &err,
            (expect){TS_ERR_INVALID, "a transformed vertex is not a finite float"});

    struct {
        ts_light_desc l;
        expect e;
    } lights[] = {
        {{.type = TS_LIGHT_AREA}, {TS_ERR_INVALID, "area lights come from shapes"}},
        {{.type = (ts_light_type)11}, {TS_ERR_INVALID, "unknown light type 11"}},
        {{.type = TS_LIGHT_POINT, .color = {-1, 0, 0}}, {TS_ERR_INVALID, "color: expected RGB ≥ 0"}},
        {{.type = TS_LIGHT_SPOT, .from = {1, 1, 1}, .to = {1, 1, 1}, .cone_angle_deg = 30},
         {TS_ERR_INVALID, "to: must differ from 'from'"}},
        {{.type = TS_LIGHT_SPOT, .to = {0, -1, 0}, .cone_angle_deg = 190}, {TS_ERR_INVALID, "cone_angle"}},
        {{.type = TS_LIGHT_SPOT, .to = {0, -1, 0}, .cone_angle_deg = 30, .cone_delta_deg = 31},
         {TS_ERR_INVALID, "cone_delta"}},
        {{.type = TS_LIGHT_DISTANT}, {TS_ERR_INVALID, "to: must differ from 'from'"}},
        {{.type = TS_LIGHT_INFINITE, .map = (const struct ts_envmap *)&lim, .to_world = ts_xform_identity()},
         {TS_ERR_INVALID, "the map was not loaded by this scene builder"}},
    };
    for (size_t i = 0; i < sizeof lights / sizeof *lights; i++)
        refused(ts_scene_builder_add_light(b, &lights[i].l, &err), &err, lights[i].e);

    /* Files need an asset folder; the triangle budget is checked before the file is read. */
    ts_mesh_data md;
    refused(ts_scene_builder_load_mesh(b, "a.obj", &md, &err), &err,
            (expect){TS_ERR_INVALID, "mesh file 'a.obj': this scene may not refer to files"});
    const struct ts_fourier_table *t = NULL;
    refused(ts_scene_builder_load_fourier(b, "a.bsdf", &t, &err), &err,
            (expect){TS_ERR_INVALID, "Fourier BSDF file 'a.bsdf'"});
    const struct ts_envmap *em = NULL;
    refused(ts_scene_builder_load_envmap(b, "sky.exr", &em, &err), &err,
            (expect){TS_ERR_INVALID, "environment map 'sky.exr'"});

    /* Nothing refused was added. */
    ts_scene_counts c;
    ts_scene_builder_counts(b, &c);
    assert_int_equal(c.materials, 2);
    assert_int_equal(c.shapes, 0);
    assert_int_equal(c.lights, 0);
    assert_int_equal(c.triangles, 0);
    /* What fits still goes in: the budget's one triangle, emitting; then no file is read. */
    ts_shape_desc one = quad();
    one.mesh = (ts_mesh){3, 1, tri_p, NULL, NULL, tri};
    one.emission = ts_rgb_gray(1);
    ok(ts_scene_builder_add_shape(b, &one, NULL, &err), &err);
    ts_scene_builder_counts(b, &c);
    assert_int_equal(c.triangles, 1);
    assert_int_equal(c.area_lights, 1);
    refused(ts_scene_builder_load_mesh(b, "a.obj", &md, &err), &err,
            (expect){TS_ERR_LIMIT, "the scene's triangles exceed the limit of 1"});
    ts_scene *s = NULL;
    ok(ts_scene_builder_finish(b, &s, &err), &err);
    assert_int_equal(s->n_lights, 1);
    assert_int_equal(s->lights[0].type, TS_LIGHT_AREA);
    assert_int_equal(s->n_materials, 2);
    assert_null(s->material_names[1]);
    ts_scene_destroy(s);
    ts_scene_builder_destroy(b);
}

/* Limits on counts, the lights' one counting area lights, at add and at finish. */
static void test_count_limits(void **state)
{
    (void)state;
    ts_scene_limits lim;
    ts_scene_limits_default(&lim);
    lim.max_materials = 1;
    lim.max_shapes = 2;
    lim.max_lights = 2;
    ts_scene_builder *b = base(&lim);
    ts_error err = {0};
    ts_material m = {.type = TS_MATERIAL_MIRROR};
    refused(ts_scene_builder_add_material(b, "n", &m, NULL, &err), &err,
            (expect){TS_ERR_LIMIT, "more than the limit of 1 materials"});
    ts_shape_desc lamp = sphere(1);
    lamp.emission = ts_rgb_gray(1);
    ok(ts_scene_builder_add_shape(b, &lamp, NULL, &err), &err);
    ts_light_desc point = {.type = TS_LIGHT_POINT, .color = ts_rgb_gray(1)};
    ok(ts_scene_builder_add_light(b, &point, &err), &err);
    refused(ts_scene_builder_add_light(b, &point, &err), &err,
            (expect){TS_ERR_LIMIT, "more than the limit of 2 lights"});
    ok(ts_scene_builder_add_shape(b, &lamp, NULL, &err), &err); /* a third light, through a shape */
    ts_shape_desc third = sphere(1);
    refused(ts_scene_builder_add_shape(b, &third, NULL, &err), &err,
            (expect){TS_ERR_LIMIT, "more than the limit of 2 shapes"});
    ts_scene *s = (ts_scene *)&lim;
    refused(ts_scene_builder_finish(b, &s, &err), &err,
            (expect){TS_ERR_LIMIT, "lights: 3 lights (with emitting triangles) is more than the limit of 2"});
    assert_null(s);
    /* Spent: every further call is refused; destroy frees what was added. */
    refused(ts_scene_builder_add_light(b, &point, &err), &err, (expect){TS_ERR_INVALID, "has finished"});
    refused(ts_scene_builder_finish(b, &s, &err), &err, (expect){TS_ERR_INVALID, "has finished"});
    ts_scene_builder_destroy(b);
}

static void test_finish_needs_settings(void **state)
{
    (void)state;
    ts_scene_builder *b = NULL;
    ts_error err = {0};
    ok(ts_scene_builder_create(NULL, NULL, &b, &err), &err);
    ts_film_desc film = {8, 8, {0, 1, 0, 1}, TS_FILTER_BOX, 0.5f};
    ok(ts_scene_builder_set_film(b, &film, &err), &err);
    ts_scene *s = NULL;
    refused(ts_scene_builder_finish(b, &s, &err), &err, (expect){TS_ERR_INVALID, "camera: not set"});
    ts_scene_builder_destroy(b);

    /* Without a digest: shards of two such scenes could not be told apart. */
    b = base(NULL);
    ts_scene_builder_destroy(b); /* destroy before finish frees everything */
    ok(ts_scene_builder_create(NULL, NULL, &b, &err), &err);
    ts_camera_desc cam = {TS_CAMERA_ORTHOGRAPHIC, {0, 0, 5}, {0, 0, 0}, {0, 1, 0}, 0, 2, 0, 1};
    ts_sampler smp = {TS_SAMPLER_SOBOL, 0};
    ts_integrator_desc in = {.type = TS_INTEGRATOR_NORMALS};
    ok(ts_scene_builder_set_film(b, &film, &err), &err);
    ok(ts_scene_builder_set_camera(b, &cam, &err), &err);
    ok(ts_scene_builder_set_sampler(b, &smp, 1, &err), &err);
    ok(ts_scene_builder_set_integrator(b, &in, &err), &err);
    refused(ts_scene_builder_finish(b, &s, &err), &err, (expect){TS_ERR_INVALID, "digest: not set"});
    ts_scene_builder_destroy(b);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_same_scene_as_json), cmocka_unit_test(test_mesh_to_world),
        cmocka_unit_test(test_settings_refused),   cmocka_unit_test(test_elements_refused),
        cmocka_unit_test(test_count_limits),       cmocka_unit_test(test_finish_needs_settings),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
