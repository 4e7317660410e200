/* test_scene.c — scene format v1: every proto/examples document loads, every case under
 * tests/scenes/invalid/ is refused with its expected sentence (expected.txt holds a part of
 * the message that must appear), and the built-in Cornell box loads with its geometry. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene/scene.h"
#include "json/scene_json.h"

static const char *source_dir(void)
{
    const char *d = getenv("TS_SOURCE_DIR");
    return d ? d : ".";
}

static int list_dir(const char *path, char names[][256], int max, int want_dirs)
{
    DIR *d = opendir(path);
    if (!d) fail_msg("cannot open %s", path);
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)) && n < max) {
        if (e->d_name[0] == '.') continue;
        size_t len = strlen(e->d_name);
        if (!want_dirs && (len < 5 || strcmp(e->d_name + len - 5, ".json") != 0)) continue;
        snprintf(names[n++], 256, "%s", e->d_name);
    }
    closedir(d);
    qsort(names, (size_t)n, 256, (int (*)(const void *, const void *))strcmp);
    return n;
}

static void test_examples_load(void **state)
{
    (void)state;
    char dir[1024], names[64][256];
    snprintf(dir, sizeof dir, "%s/proto/examples", source_dir());
    int n = list_dir(dir, names, 64, 0);
    assert_true(n >= 5);
    for (int i = 0; i < n; i++) {
        char path[1400];
        snprintf(path, sizeof path, "%s/%s", dir, names[i]);
        ts_scene *s = NULL;
        ts_error err = {0};
        ts_status st = ts_scene_load_file(path, NULL, &s, &err);
        if (st) fail_msg("%s: %s", names[i], err.message);
        assert_non_null(s);
        assert_non_null(s->accel);
        ts_scene_destroy(s);
    }
}

static void test_invalid_cases(void **state)
{
    (void)state;
    char dir[1024], names[128][256];
    snprintf(dir, sizeof dir, "%s/tests/scenes/invalid", source_dir());
    int n = list_dir(dir, names, 128, 1);
    assert_true(n >= 30);
    for (int i = 0; i < n; i++) {
        char path[1400], expected_path[1400], expected[512] = "";
        snprintf(path, sizeof path, "%s/%s/scene.json", dir, names[i]);
        snprintf(expected_path, sizeof expected_path, "%s/%s/expected.txt", dir, names[i]);
        FILE *f = fopen(expected_path, "r");
        if (!f) fail_msg("%s: no expected.txt", names[i]);
        if (!fgets(expected, sizeof expected, f)) expected[0] = '\0';
        fclose(f);
        expected[strcspn(expected, "\n")] = '\0';
        assert_true(expected[0] != '\0');
        ts_scene *s = NULL;
        ts_error err = {0};
        ts_status st = ts_scene_load_file(path, NULL, &s, &err);
        if (st == TS_OK) fail_msg("%s: loaded, but should have been refused with \"%s\"", names[i], expected);
        assert_null(s);
        if (!strstr(err.message, expected))
            fail_msg("%s: message \"%s\" does not contain \"%s\"", names[i], err.message, expected);
    }
}

static void test_builtin_cornell_box(void **state)
{
    (void)state;
    ts_scene *s = NULL;
    ts_error err = {0};
    assert_int_equal(ts_scene_load_builtin(NULL, &s, &err), TS_OK);
    assert_string_equal(s->name, "cornell-box");
    assert_int_equal(s->width, 512);
    assert_int_equal(s->height, 512);
    assert_int_equal(s->spp, 64);
    assert_int_equal(s->n_shapes, 8);
    assert_int_equal(s->n_materials, 4);
    /* The light quad is two emitting triangles forming a rectangle: one area light. */
    assert_int_equal(s->n_lights, 1);
    assert_int_equal(s->lights[0].type, TS_LIGHT_AREA);
    assert_true(s->lights[0].rect);
    assert_true(s->shapes[0].emissive);
    /* Room bounds: x in [0, 556], y in [0, 548.8], z in [0, 559.2]. */
    assert_float_equal(s->bounds.lo.y, 0, 0);
    assert_float_equal(s->bounds.hi.y, 548.8f, 1e-3f);
    assert_float_equal(s->bounds.hi.z, 559.2f, 1e-3f);
    /* The embedded copy is the shipped file. */
    size_t len;
    const char *text = ts_scene_builtin_text(&len);
    char path[1024];
    snprintf(path, sizeof path, "%s/scenes/cornell-box.json", source_dir());
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    char *buf = malloc(len + 1);
    size_t got = fread(buf, 1, len + 1, f);
    fclose(f);
    assert_int_equal(got, len);
    assert_memory_equal(buf, text, len);
    free(buf);
    ts_scene_destroy(s);
}

static void test_transform_order_and_mirror(void **state)
{
    (void)state;
    /* scale 2 then translate +x 1: a sphere at the origin of radius 1 spans x in [-1, 3]. */
    const char *doc = "{\"tessera\":1,\"camera\":{\"from\":[0,0,10],\"to\":[0,0,0]},\"materials\":{\"m\":{\"type\":"
                      "\"diffuse\"}},\"shapes\":[{\"type\":\"sphere\",\"radius\":1,\"material\":\"m\",\"transform\":"
                      "[{\"scale\":2},{\"translate\":[1,0,0]}]},{\"type\":\"mesh\",\"positions\":[0,0,0,1,0,0,0,1,0],"
                      "\"indices\":[0,1,2],\"material\":\"m\",\"transform\":[{\"scale\":[-1,1,1]}]}]}";
    ts_scene *s = NULL;
    ts_error err = {0};
    ts_status st = ts_scene_load_text(doc, strlen(doc), NULL, "t", NULL, &s, &err);
    if (st) fail_msg("%s", err.message);
    ts_bounds3 b = ts_shape_bounds(&s->shapes[0]);
    assert_float_equal(b.lo.x, -1, 1e-5);
    assert_float_equal(b.hi.x, 3, 1e-5);
    /* The mirrored triangle keeps facing +z, as in object space (winding reversed). */
    const ts_mesh *m = &s->shapes[1].mesh;
    ts_vec3 p[3];
    for (int k = 0; k < 3; k++) {
        uint32_t i = m->index[k];
        p[k] = (ts_vec3){m->p[3 * i], m->p[3 * i + 1], m->p[3 * i + 2]};
    }
    ts_vec3 n = ts_vec3_cross(ts_vec3_sub(p[1], p[0]), ts_vec3_sub(p[2], p[0]));
    assert_true(n.z > 0);
    ts_scene_destroy(s);
}

static void test_text_scene_may_not_reference_files(void **state)
{
    (void)state;
    const char *doc = "{\"tessera\":1,\"camera\":{\"from\":[0,0,10],\"to\":[0,0,0]},\"materials\":{\"m\":{\"type\":"
                      "\"diffuse\"}},\"shapes\":[{\"type\":\"mesh\",\"file\":\"a.obj\",\"material\":\"m\"}]}";
    ts_scene *s = NULL;
    ts_error err = {0};
    assert_int_not_equal(ts_scene_load_text(doc, strlen(doc), NULL, "t", NULL, &s, &err), TS_OK);
    assert_null(s);
    assert_non_null(strstr(err.message, "shapes[0].file"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_examples_load),
        cmocka_unit_test(test_invalid_cases),
        cmocka_unit_test(test_builtin_cornell_box),
        cmocka_unit_test(test_transform_order_and_mirror),
        cmocka_unit_test(test_text_scene_may_not_reference_files),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
