/* test_cli.c — `tessera render` as a user runs it: exit statuses, messages, outputs, and
 * thread-count determinism of the written EXR (every channel bit-identical; the render-time
 * attribute is the only header field allowed to differ). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <fcntl.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "cli_support.h"
#include "image/exr.h"
#include "image/image.h"

static char tmpdir[256];
static char errlog[512];

static int run(const char *const *args) { return cli_run(errlog, args, NULL); }
static const char *read_log(void) { return cli_read_log(errlog); }

static void path_in_tmp(char *out, size_t n, const char *name) { snprintf(out, n, "%s/%s", tmpdir, name); }

static void write_file(const char *path, const char *text) { cli_write_file(path, text); }
static bool exists(const char *path) { return cli_exists(path); }

static int setup(void **state)
{
    (void)state;
    snprintf(tmpdir, sizeof tmpdir, "/tmp/tessera-cli-XXXXXX");
    if (!mkdtemp(tmpdir)) return -1;
    path_in_tmp(errlog, sizeof errlog, "stderr.txt");
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    char cmd[600];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmpdir);
    return system(cmd) == 0 ? 0 : -1;
}

static const char *small_scene =
    "{\"tessera\":1,\"camera\":{\"from\":[0,1,5],\"to\":[0,0.5,0],\"fov\":40},\"film\":{\"width\":48,\"height\":"
    "32},\"sampler\":{\"spp\":4},\"integrator\":{\"type\":\"ao\"},\"materials\":{\"m\":{\"type\":\"diffuse\"}},"
    "\"shapes\":[{\"type\":\"sphere\",\"center\":[0,0.5,0],\"radius\":0.5,\"material\":\"m\"},{\"type\":\"disk\","
    "\"normal\":[0,1,0],\"radius\":5,\"material\":\"m\"}]}";

static void test_threads_give_identical_exr(void **state)
{
    (void)state;
    char scene[512], a[512], b[512], png[512];
    path_in_tmp(scene, sizeof scene, "small.json");
    path_in_tmp(a, sizeof a, "a.exr");
    path_in_tmp(b, sizeof b, "b.exr");
    path_in_tmp(png, sizeof png, "a.png");
    write_file(scene, small_scene);
    const char *args1[] = {"render", scene, "--threads", "1", "-o", a, "-o", png, "--quiet", NULL};
    const char *args2[] = {"render", scene, "--threads", "2", "-o", b, "--quiet", NULL};
    assert_int_equal(run(args1), 0);
    assert_int_equal(run(args2), 0);
    assert_true(exists(png));
    ts_image ia, ib;
    ts_error err = {0};
    assert_int_equal(ts_exr_read(a, &ia, &err), TS_OK);
    assert_int_equal(ts_exr_read(b, &ib, &err), TS_OK);
    assert_int_equal(ia.width, 48);
    assert_int_equal(ia.height, 32);
    assert_int_equal(ia.n_channels, ib.n_channels);
    assert_memory_equal(ia.data, ib.data, sizeof(float) * 48 * 32 * (size_t)ia.n_channels);
    const ts_image_attr *spp = ts_image_attr_find(&ia, "tessera_spp");
    assert_non_null(spp);
    assert_int_equal(spp->i, 4);
    assert_non_null(ts_image_attr_find(&ia, "tessera_render_time_s"));
    ts_image_fini(&ia);
    ts_image_fini(&ib);
}

static void test_bad_scene_exit_1_and_nothing_written(void **state)
{
    (void)state;
    char scene[512], out[512];
    path_in_tmp(scene, sizeof scene, "bad.json");
    path_in_tmp(out, sizeof out, "bad.exr");
    write_file(scene, "{\"tessera\":1,\"camera\":{\"from\":[0,0,5],\"to\":[0,0,0]},\"materials\":{\"m\":{\"type\":"
                      "\"diffuse\"}},\"shapes\":[{\"type\":\"sphere\",\"radius\":-1,\"material\":\"m\"}]}");
    const char *args[] = {"render", scene, "-o", out, NULL};
    assert_int_equal(run(args), 1);
    assert_non_null(strstr(read_log(), "shapes[0].radius: expected a positive number, got -1"));
    assert_false(exists(out));
    const char *missing[] = {"render", "/nonexistent/scene.json", "-o", out, NULL};
    assert_int_equal(run(missing), 1);
    assert_false(exists(out));
}

static void test_usage_errors_exit_2(void **state)
{
    (void)state;
    const char *a1[] = {"render", "--spp", "zero", NULL};
    assert_int_equal(run(a1), 2);
    assert_non_null(strstr(read_log(), "--spp"));
    const char *a2[] = {"render", "-o", "out.tiff", NULL};
    assert_int_equal(run(a2), 2);
    assert_non_null(strstr(read_log(), ".exr or .png"));
    const char *a3[] = {"frobnicate", NULL};
    assert_int_equal(run(a3), 2);
    const char *a4[] = {"render", "--bogus", NULL};
    assert_int_equal(run(a4), 2);
    const char *a5[] = {NULL};
    assert_int_equal(run(a5), 2);
}

static void test_builtin_default(void **state)
{
    (void)state;
    char out[512];
    path_in_tmp(out, sizeof out, "cornell.png");
    const char *args[] = {"render", "--spp", "1", "-o", out, NULL};
    assert_int_equal(run(args), 0);
    assert_true(exists(out));
    assert_non_null(strstr(read_log(), "cornell-box"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_threads_give_identical_exr),
        cmocka_unit_test(test_bad_scene_exit_1_and_nothing_written),
        cmocka_unit_test(test_usage_errors_exit_2),
        cmocka_unit_test(test_builtin_default),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
